/* glint: command-line access to glint's core, for scripting and tests.
 *
 * Every subcommand validates its arguments, prints a clear message on
 * error ("glint fit: --res 3 outside 4..512") and exits non-zero:
 *   1  bad usage or invalid input
 *   2  I/O error
 *   3  numerical failure
 * See `glint help` for the list. */
#include <errno.h>
#include <stdarg.h>
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "brdf.h"
#include "fit.h"
#include "fsio.h"
#include "gbuf.h"
#include "glr.h"
#include "hf.h"
#include "img.h"
#include "material.h"
#include "paint.h"
#include "raster.h"
#include "samples.h"
#include "scene.h"

#define GLINT_VERSION "0.1.0"

static const char *cmd_name = "glint";

static int fail(int code, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));

static int fail(int code, const char *fmt, ...)
{
    va_list ap;
    fprintf(stderr, "%s: ", cmd_name);
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fputc('\n', stderr);
    return code;
}

/* Exit status for a glint error code. */
static int status_of(int code)
{
    switch (code) {
    case GLINT_EIO: return 2;
    case GLINT_ENUMERIC: case GLINT_EINTERNAL: return 3;
    default: return 1;
    }
}

static int fail_err(const glint_err *e)
{
    return fail(status_of(e->code), "%s", e->msg[0] ? e->msg : glint_strerror(e->code));
}

/* ---- argument parsing ------------------------------------------------------- */

static int parse_int(const char *s, const char *what, long lo, long hi, int *out)
{
    char *end;
    long v;
    errno = 0;
    v = strtol(s, &end, 10);
    if (end == s || *end || errno || v < lo || v > hi)
        return fail(1, "%s '%s' must be a whole number in %ld..%ld", what, s, lo, hi);
    *out = (int)v;
    return 0;
}

static int parse_double(const char *s, const char *what, double lo, double hi, double *out)
{
    char *end;
    double v = strtod(s, &end);
    if (end == s || *end || !isfinite(v) || v < lo || v > hi)
        return fail(1, "%s '%s' must be a finite number in [%g, %g]", what, s, lo, hi);
    *out = v;
    return 0;
}

static int parse_vec3(const char *s, const char *what, double out[3])
{
    char *end;
    const char *p = s;
    for (int i = 0; i < 3; i++) {
        out[i] = strtod(p, &end);
        if (end == p || !isfinite(out[i]) || fabs(out[i]) > 1e6)
            return fail(1, "%s '%s' must be three finite numbers x,y,z", what, s);
        p = end;
        if (i < 2) {
            if (*p != ',')
                return fail(1, "%s '%s' must be three numbers separated by commas", what, s);
            p++;
        }
    }
    if (*p)
        return fail(1, "%s '%s' has trailing characters", what, s);
    return 0;
}

static int parse_size(const char *s, int *w, int *h)
{
    int n1, n2;
    char x;
    if (sscanf(s, "%d%c%d", &n1, &x, &n2) == 3 && (x == 'x' || x == 'X')) {
        char buf[64];
        snprintf(buf, sizeof buf, "%dx%d", n1, n2);
        if (strcmp(buf, s) != 0)
            return fail(1, "size '%s' must be WxH or N", s);
    } else {
        if (parse_int(s, "size", SCENE_MIN_SIZE, SCENE_MAX_SIZE, &n1))
            return 1;
        n2 = n1;
    }
    if (n1 < SCENE_MIN_SIZE || n1 > SCENE_MAX_SIZE || n2 < SCENE_MIN_SIZE || n2 > SCENE_MAX_SIZE)
        return fail(1, "size %dx%d outside %d..%d", n1, n2, SCENE_MIN_SIZE, SCENE_MAX_SIZE);
    *w = n1;
    *h = n2;
    return 0;
}

/* Fit options shared by fit and fit-samples. */
typedef struct fit_opts {
    fit_params p;
    const char *cache_dir;
} fit_opts;

enum { OPT_RES = 1000, OPT_LAMBDA, OPT_REG, OPT_MAP, OPT_MODEL, OPT_PREC, OPT_ROUTE,
       OPT_RCOND, OPT_CACHE, OPT_NOCACHE };

#define FIT_LONGOPTS                                                       \
    {"res", required_argument, 0, OPT_RES},                                \
    {"lambda", required_argument, 0, OPT_LAMBDA},                          \
    {"reg", required_argument, 0, OPT_REG},                                \
    {"map", required_argument, 0, OPT_MAP},                                \
    {"model", required_argument, 0, OPT_MODEL},                            \
    {"precision", required_argument, 0, OPT_PREC},                         \
    {"route", required_argument, 0, OPT_ROUTE},                            \
    {"rcond", required_argument, 0, OPT_RCOND},                            \
    {"cache-dir", required_argument, 0, OPT_CACHE},                        \
    {"no-cache", no_argument, 0, OPT_NOCACHE}

static const char *default_cache_dir(void)
{
    static char buf[4096];
    const char *x = getenv("XDG_CACHE_HOME"), *home = getenv("HOME");
    if (x && *x)
        snprintf(buf, sizeof buf, "%s/glint", x);
    else if (home && *home)
        snprintf(buf, sizeof buf, "%s/.cache/glint", home);
    else
        return NULL;
    return buf;
}

static void fit_opts_default(fit_opts *o)
{
    fit_params_default(&o->p);
    o->cache_dir = default_cache_dir();
}

/* Returns 0 if handled, -1 if not a fit option, > 0 on error. */
static int fit_opt(fit_opts *o, int c, const char *arg)
{
    glint_err e;
    switch (c) {
    case OPT_RES:
        return parse_int(arg, "--res", HF_RES_MIN, HF_RES_MAX, &o->p.res);
    case OPT_LAMBDA:
        return parse_double(arg, "--lambda", 0.0, HF_LAMBDA_MAX, &o->p.lambda);
    case OPT_REG:
        return hf_reg_parse(arg, &o->p.reg, &e) ? fail_err(&e) : 0;
    case OPT_MAP:
        return hf_map_parse(arg, &o->p.map, &e) ? fail_err(&e) : 0;
    case OPT_MODEL:
        if (strcmp(arg, "radiance") == 0) o->p.model = HF_MODEL_RADIANCE;
        else if (strcmp(arg, "brdf") == 0) o->p.model = HF_MODEL_BRDF;
        else return fail(1, "--model '%s': radiance or brdf", arg);
        return 0;
    case OPT_PREC:
        if (strcmp(arg, "double") == 0) o->p.prec = HF_F64;
        else if (strcmp(arg, "single") == 0) o->p.prec = HF_F32;
        else return fail(1, "--precision '%s': double or single", arg);
        return 0;
    case OPT_ROUTE:
        if (strcmp(arg, "eig") == 0) o->p.route = HF_ROUTE_EIG;
        else if (strcmp(arg, "svd") == 0) o->p.route = HF_ROUTE_SVD;
        else return fail(1, "--route '%s': eig or svd", arg);
        return 0;
    case OPT_RCOND:
        return parse_double(arg, "--rcond", 1e-16, 0.5, &o->p.rcond);
    case OPT_CACHE:
        o->cache_dir = arg;
        return 0;
    case OPT_NOCACHE:
        o->cache_dir = NULL;
        return 0;
    default:
        return -1;
    }
}

/* ---- shared steps ----------------------------------------------------------- */

static int load_scene(const char *path, scene *sc)
{
    glint_err e;
    if (scene_load(path, sc, &e))
        return fail_err(&e);
    return 0;
}

static int raster_all(const scene *sc, gbuf **g)
{
    glint_err e;
    if (raster_scene(sc, g, &e))
        return fail_err(&e);
    return 0;
}

/* Find view_KK.{exr,hdr,png,jpg,jpeg} in dir; returns 1 and the path if found. */
static int find_painting(const char *dir, int view, char *path, size_t len)
{
    static const char *ext[] = {"exr", "hdr", "png", "jpg", "jpeg"};
    struct stat st;
    for (unsigned i = 0; i < sizeof ext / sizeof ext[0]; i++) {
        snprintf(path, len, "%s/view_%02d.%s", dir, view, ext[i]);
        if (stat(path, &st) == 0)
            return 1;
    }
    return 0;
}

/* Read the paintings of a scene: from a directory (views without a file are
 * not used) or from a list of files (one per view, in order). */
static int read_paintings(const scene *sc, const char *dir, char **files, int nfiles,
                          img *imgs, unsigned char *use)
{
    glint_err e;
    int found = 0;
    if (!dir && nfiles != sc->nviews)
        return fail(1, "expected %d painting files (one per view), got %d; or use --paintings DIR",
                    sc->nviews, nfiles);
    for (int v = 0; v < sc->nviews; v++) {
        char path[4096];
        const char *p = NULL;
        use[v] = 0;
        if (dir) {
            if (find_painting(dir, v, path, sizeof path))
                p = path;
        } else {
            p = files[v];
        }
        if (!p)
            continue;
        if (img_read(p, &imgs[v], &e)) {
            glint_err_prefix(&e, "painting of view %d (%s)", v, p);
            return fail_err(&e);
        }
        if (imgs[v].width != sc->width || imgs[v].height != sc->height)
            return fail(1, "painting %s is %dx%d but the scene renders %dx%d", p, imgs[v].width,
                        imgs[v].height, sc->width, sc->height);
        use[v] = 1;
        found++;
    }
    if (!found)
        return fail(1, "no painting found in %s (expected view_00.exr, view_01.png, ...)", dir);
    return 0;
}

static void free_imgs(img *imgs, int n)
{
    if (!imgs)
        return;
    for (int i = 0; i < n; i++)
        img_free(&imgs[i]);
    free(imgs);
}

static int write_json_file(const char *path, json_t *j)
{
    glint_err e;
    char *text = json_dumps(j, JSON_INDENT(2) | JSON_REAL_PRECISION(10));
    int rc;
    if (!text)
        return fail(1, "cannot serialize JSON");
    rc = fsio_write_atomic(path, text, strlen(text), &e);
    free(text);
    return rc ? fail_err(&e) : 0;
}

static void print_json(json_t *j)
{
    char *text = json_dumps(j, JSON_INDENT(2) | JSON_REAL_PRECISION(10));
    if (text) {
        puts(text);
        free(text);
    }
}

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

static int cmd_scene(int argc, char **argv)
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

static int cmd_gbuffer(int argc, char **argv)
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

/* ---- paint -------------------------------------------------------------------- */

static int cmd_paint(int argc, char **argv)
{
    static const struct option lo[] = {
        {"brdf", required_argument, 0, 'b'}, {"out", required_argument, 0, 'o'},
        {"scale", required_argument, 0, 's'}, {"format", required_argument, 0, 'f'},
        {0, 0, 0, 0}};
    const char *out = NULL, *fmt = "exr", *spec = NULL;
    double scale = 0.0, used = 0.0;
    int c, rc;
    scene sc;
    gbuf *g = NULL;
    img *imgs = NULL;
    brdf b;
    glint_err e;

    optind = 1;
    while ((c = getopt_long(argc, argv, "b:o:s:f:", lo, NULL)) != -1) {
        switch (c) {
        case 'b': spec = optarg; break;
        case 'o': out = optarg; break;
        case 's':
            if ((rc = parse_double(optarg, "--scale", 1e-12, 1e12, &scale)))
                return rc;
            break;
        case 'f':
            if (strcmp(optarg, "exr") && strcmp(optarg, "png") && strcmp(optarg, "hdr"))
                return fail(1, "--format '%s': exr, png or hdr", optarg);
            fmt = optarg;
            break;
        default:
            return fail(1, "usage: glint paint scene.json --brdf SPEC -o DIR [--scale S] [--format exr|png|hdr]");
        }
    }
    if (!out || !spec || optind != argc - 1)
        return fail(1, "usage: glint paint scene.json --brdf SPEC -o DIR [--scale S] [--format exr|png|hdr]");
    if (brdf_parse(spec, &b, &e))
        return fail_err(&e);
    if ((rc = load_scene(argv[optind], &sc)))
        return rc;
    if ((rc = raster_all(&sc, &g)))
        goto done;
    imgs = calloc((size_t)sc.nviews, sizeof *imgs);
    if (!imgs) {
        rc = fail(1, "out of memory");
        goto done;
    }
    if (paint_views(&b, g, sc.views, sc.nviews, scale, imgs, &used, &e)) {
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
    return rc;
}

/* ---- fit ---------------------------------------------------------------------- */

static int save_material(const material *m, const char *out)
{
    glint_err e;
    if (material_save(m, out, &e))
        return fail_err(&e);
    return 0;
}

static int cmd_fit(int argc, char **argv)
{
    static const struct option lo[] = {{"paintings", required_argument, 0, 'p'},
                                       {"out", required_argument, 0, 'o'},
                                       {"quiet", no_argument, 0, 'q'},
                                       FIT_LONGOPTS,
                                       {0, 0, 0, 0}};
    fit_opts o;
    const char *dir = NULL, *out = NULL, *scene_path;
    int c, rc = 0, quiet = 0;
    scene sc;
    gbuf *g = NULL;
    img *imgs = NULL;
    unsigned char *use = NULL;
    fit_prep fp;
    material m;
    glint_err e;

    memset(&fp, 0, sizeof fp);
    memset(&m, 0, sizeof m);
    fit_opts_default(&o);
    optind = 1;
    while ((c = getopt_long(argc, argv, "p:o:q", lo, NULL)) != -1) {
        if (c == 'p') dir = optarg;
        else if (c == 'o') out = optarg;
        else if (c == 'q') quiet = 1;
        else if ((rc = fit_opt(&o, c, optarg)) != 0)
            return rc > 0 ? rc : fail(1, "usage: glint fit scene.json (--paintings DIR | FILE...) -o MATDIR [fit options]");
    }
    if (!out || optind >= argc)
        return fail(1, "usage: glint fit scene.json (--paintings DIR | FILE...) -o MATDIR [fit options]");
    scene_path = argv[optind++];
    if ((rc = load_scene(scene_path, &sc)))
        return rc;
    imgs = calloc((size_t)sc.nviews, sizeof *imgs);
    use = calloc((size_t)sc.nviews, 1);
    if (!imgs || !use) {
        rc = fail(1, "out of memory");
        goto done;
    }
    if ((rc = read_paintings(&sc, dir, argv + optind, argc - optind, imgs, use)))
        goto done;
    if ((rc = raster_all(&sc, &g)))
        goto done;
    if (fit_prepare(&fp, &sc, g, use, &o.p, o.cache_dir, &e) ||
        fit_run(&fp, imgs, NULL, &m, &e)) {
        rc = fail_err(&e);
        goto done;
    }
    {
        char hash[33];
        scene_hash(&sc, hash);
        json_object_set_new(m.info, "scene_hash", json_string(hash));
        json_object_set_new(m.info, "scene", json_string(scene_path));
    }
    if ((rc = save_material(&m, out)))
        goto done;
    if (!quiet)
        print_json(m.info);
done:
    material_free(&m);
    fit_prep_free(&fp);
    free_imgs(imgs, sc.nviews);
    free(use);
    raster_free_all(g, sc.nviews);
    scene_free(&sc);
    return rc;
}

/* ---- rendering engines ------------------------------------------------------- */

/* The EGL renderer, opened on first use (NULL with a message on stderr if no
 * platform works: callers fall back to the CPU unless --engine egl). */
static glr *gl_ctx;
static int gl_tried;

static glr *gl_get(int required)
{
    glint_err e;
    if (!gl_tried) {
        gl_tried = 1;
        if (glr_open(&gl_ctx, &e)) {
            gl_ctx = NULL;
            if (required)
                fail(status_of(e.code), "%s", e.msg);
            else
                fprintf(stderr, "%s: EGL unavailable (%s); rendering on the CPU\n", cmd_name,
                        e.msg);
        }
    }
    return gl_ctx;
}

static void gl_release(void)
{
    if (gl_ctx)
        glr_close(gl_ctx);
    gl_ctx = NULL;
}

/* Render a material preview with the chosen engine ("auto", "egl", "cpu"). */
static int render_material(const material *m, const mesh *msh, const scene_view *v, int w,
                           int h, const char *engine, img *out)
{
    glint_err e;
    glr *g = strcmp(engine, "cpu") == 0 ? NULL : gl_get(strcmp(engine, "egl") == 0);
    if (!g && strcmp(engine, "egl") == 0)
        return 1;
    if (g) {
        glr_mesh *gm = NULL;
        int rc = glr_mesh_upload(g, msh, &gm, &e);
        if (!rc)
            rc = glr_preview(g, gm, m, v, w, h, 0.0f, out, &e);
        glr_mesh_free(g, gm);
        return rc ? fail_err(&e) : 0;
    }
    return material_render(m, msh, v, w, h, out, &e) ? fail_err(&e) : 0;
}

/* ---- base renders -------------------------------------------------------------- */

static int cmd_base_render(int argc, char **argv)
{
    static const struct option lo[] = {{"out", required_argument, 0, 'o'},
                                       {"brdf", required_argument, 0, 'b'},
                                       {"scale", required_argument, 0, 's'},
                                       {"engine", required_argument, 0, 'g'},
                                       {"format", required_argument, 0, 'f'},
                                       {0, 0, 0, 0}};
    const char *out = NULL, *spec = "lambert:kd=0.6", *engine = "auto", *fmt = "png";
    double scale = M_PI;
    int c, rc = 0;
    scene sc;
    brdf b;
    glint_err e;
    glr *g = NULL;
    glr_mesh *gm = NULL;
    gbuf *gb = NULL;

    optind = 1;
    while ((c = getopt_long(argc, argv, "o:b:s:g:f:", lo, NULL)) != -1) {
        if (c == 'o') out = optarg;
        else if (c == 'b') spec = optarg;
        else if (c == 's') { if ((rc = parse_double(optarg, "--scale", 1e-9, 1e9, &scale))) return rc; }
        else if (c == 'g') engine = optarg;
        else if (c == 'f') fmt = optarg;
        else return fail(1, "usage: glint base-render scene.json -o DIR [--brdf SPEC] [--scale S] [--engine auto|egl|cpu] [--format png|exr]");
    }
    if (!out || optind != argc - 1)
        return fail(1, "usage: glint base-render scene.json -o DIR [--brdf SPEC] [--scale S] [--engine auto|egl|cpu] [--format png|exr]");
    if (strcmp(engine, "auto") && strcmp(engine, "egl") && strcmp(engine, "cpu"))
        return fail(1, "--engine '%s': auto, egl or cpu", engine);
    if (strcmp(fmt, "png") && strcmp(fmt, "exr"))
        return fail(1, "--format '%s': png or exr", fmt);
    if (brdf_parse(spec, &b, &e))
        return fail_err(&e);
    if ((rc = load_scene(argv[optind], &sc)))
        return rc;
    if (fsio_mkdirs(out, &e)) {
        rc = fail_err(&e);
        goto done;
    }
    if (strcmp(engine, "cpu") != 0)
        g = gl_get(strcmp(engine, "egl") == 0);
    if (!g && strcmp(engine, "egl") == 0) {
        rc = 1;
        goto done;
    }
    if (g && glr_mesh_upload(g, &sc.mesh, &gm, &e)) {
        rc = fail_err(&e);
        goto done;
    }
    if (!g && (rc = raster_all(&sc, &gb)))
        goto done;
    for (int v = 0; v < sc.nviews; v++) {
        img im = {0};
        char path[4096];
        int r;
        if (g) {
            r = glr_base_render(g, gm, &sc.views[v], sc.width, sc.height, &b, scale, 0.0f, &im, &e);
        } else {
            r = paint_views(&b, &gb[v], &sc.views[v], 1, scale, &im, NULL, &e);
        }
        snprintf(path, sizeof path, "%s/view_%02d.%s", out, v, fmt);
        if (r || img_write(path, &im, &e)) {
            img_free(&im);
            rc = fail_err(&e);
            goto done;
        }
        img_free(&im);
        printf("%s\n", path);
    }
done:
    if (g)
        glr_mesh_free(g, gm);
    raster_free_all(gb, sc.nviews);
    scene_free(&sc);
    return rc;
}

/* ---- shader export -------------------------------------------------------------- */

static int cmd_export_shader(int argc, char **argv)
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

/* ---- render ------------------------------------------------------------------- */

static int cmd_render(int argc, char **argv)
{
    static const struct option lo[] = {
        {"scene", required_argument, 0, 's'}, {"view", required_argument, 0, 'v'},
        {"eye", required_argument, 0, 'e'}, {"target", required_argument, 0, 't'},
        {"light", required_argument, 0, 'l'}, {"fov", required_argument, 0, 'f'},
        {"intensity", required_argument, 0, 'i'}, {"size", required_argument, 0, 'z'},
        {"engine", required_argument, 0, 'g'}, {"out", required_argument, 0, 'o'},
        {0, 0, 0, 0}};
    const char *scene_path = NULL, *out = NULL, *engine = "auto";
    int c, rc = 0, view = -1, w = 0, h = 0, have_eye = 0, have_light = 0;
    double eye[3], target[3] = {0, 0, 0}, light[3], fov = 0, intensity = 1.0;
    scene sc;
    material m;
    scene_view v;
    img im = {0};
    glint_err e;

    memset(&sc, 0, sizeof sc);
    optind = 1;
    while ((c = getopt_long(argc, argv, "s:v:o:", lo, NULL)) != -1) {
        switch (c) {
        case 's': scene_path = optarg; break;
        case 'v': if ((rc = parse_int(optarg, "--view", 0, SCENE_MAX_VIEWS - 1, &view))) return rc; break;
        case 'e': if ((rc = parse_vec3(optarg, "--eye", eye))) return rc; have_eye = 1; break;
        case 't': if ((rc = parse_vec3(optarg, "--target", target))) return rc; break;
        case 'l': if ((rc = parse_vec3(optarg, "--light", light))) return rc; have_light = 1; break;
        case 'f': if ((rc = parse_double(optarg, "--fov", 1.0, 170.0, &fov))) return rc; break;
        case 'i': if ((rc = parse_double(optarg, "--intensity", 0.0, 1e9, &intensity))) return rc; break;
        case 'z': if ((rc = parse_size(optarg, &w, &h))) return rc; break;
        case 'g':
            if (strcmp(optarg, "auto") && strcmp(optarg, "egl") && strcmp(optarg, "cpu"))
                return fail(1, "--engine '%s': auto, egl or cpu", optarg);
            engine = optarg;
            break;
        case 'o': out = optarg; break;
        default:
            return fail(1, "usage: glint render MATDIR --scene scene.json (--view K | --eye X,Y,Z --light X,Y,Z) [--size WxH] [--engine auto|egl|cpu] -o image.png|exr");
        }
    }
    if (!out || !scene_path || optind != argc - 1)
        return fail(1, "usage: glint render MATDIR --scene scene.json (--view K | --eye X,Y,Z --light X,Y,Z) [--size WxH] -o image.png|exr");
    if (view < 0 && !(have_eye && have_light))
        return fail(1, "render needs --view K, or both --eye and --light");
    if (material_load(argv[optind], &m, &e))
        return fail_err(&e);
    if ((rc = load_scene(scene_path, &sc)))
        goto done;
    if (view >= 0) {
        if (view >= sc.nviews) {
            rc = fail(1, "--view %d: the scene has %d views", view, sc.nviews);
            goto done;
        }
        v = sc.views[view];
    } else {
        memset(&v, 0, sizeof v);
        v.half_fov = sc.views[0].half_fov;
        v.light_intensity = 1.0;
        v.light_deg = -1.0;
    }
    if (have_eye) memcpy(v.eye, eye, sizeof eye);
    if (have_eye) memcpy(v.target, target, sizeof target);
    if (have_light) memcpy(v.light, light, sizeof light);
    if (fov > 0) v.half_fov = 0.5 * fov * M_PI / 180.0;
    v.light_intensity = intensity;
    if (!w) {
        w = sc.width;
        h = sc.height;
    }
    {
        double d[3] = {v.target[0] - v.eye[0], v.target[1] - v.eye[1], v.target[2] - v.eye[2]};
        if (d[0] * d[0] + d[1] * d[1] + d[2] * d[2] < 1e-12) {
            rc = fail(1, "--eye and --target coincide");
            goto done;
        }
    }
    if ((rc = render_material(&m, &sc.mesh, &v, w, h, engine, &im)))
        goto done;
    if (img_write(out, &im, &e)) {
        rc = fail_err(&e);
        goto done;
    }
    printf("%s\n", out);
done:
    img_free(&im);
    material_free(&m);
    scene_free(&sc);
    return rc;
}

/* ---- eval --------------------------------------------------------------------- */

static int cmd_eval(int argc, char **argv)
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
        return fail(1, "usage: glint eval MATDIR --dirs FILE [-o OUT]  (FILE: lines 'nx ny nz wix wiy wiz wox woy woz', or 'wix wiy wiz wox woy woz' with n = +z)");
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
        double v[9], n[3], wi[3], wo[3], rgb[3];
        int got;
        lineno++;
        if (line[0] == '#' || line[strspn(line, " \t\r\n")] == '\0')
            continue;
        got = sscanf(line, "%lf %lf %lf %lf %lf %lf %lf %lf %lf", &v[0], &v[1], &v[2], &v[3],
                     &v[4], &v[5], &v[6], &v[7], &v[8]);
        if (got != 6 && got != 9) {
            rc = fail(1, "%s line %ld: expected 6 or 9 numbers", dirs, lineno);
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
        material_eval(&m, n, wi, wo, rgb);
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

/* ---- samples export / fit ------------------------------------------------------- */

static int cmd_export_samples(int argc, char **argv)
{
    static const struct option lo[] = {{"paintings", required_argument, 0, 'p'},
                                       {"channel", required_argument, 0, 'c'},
                                       {"out", required_argument, 0, 'o'},
                                       {0, 0, 0, 0}};
    const char *dir = NULL, *out = NULL;
    int c, rc = 0, channel = 0;
    scene sc;
    gbuf *g = NULL;
    img *imgs = NULL;
    unsigned char *use = NULL;
    samples s;
    float *rgb = NULL;
    glint_err e;
    char hash[33];

    memset(&s, 0, sizeof s);
    optind = 1;
    while ((c = getopt_long(argc, argv, "p:c:o:", lo, NULL)) != -1) {
        if (c == 'p') dir = optarg;
        else if (c == 'o') out = optarg;
        else if (c == 'c') { if ((rc = parse_int(optarg, "--channel", 0, 2, &channel))) return rc; }
        else return fail(1, "usage: glint export-samples scene.json [--paintings DIR] [--channel 0|1|2] -o samples.txt");
    }
    if (!out || optind != argc - 1)
        return fail(1, "usage: glint export-samples scene.json [--paintings DIR] [--channel 0|1|2] -o samples.txt");
    if ((rc = load_scene(argv[optind], &sc)))
        return rc;
    imgs = calloc((size_t)sc.nviews, sizeof *imgs);
    use = calloc((size_t)sc.nviews, 1);
    if (!imgs || !use) {
        rc = fail(1, "out of memory");
        goto done;
    }
    memset(use, 1, (size_t)sc.nviews);
    if (dir && (rc = read_paintings(&sc, dir, NULL, 0, imgs, use)))
        goto done;
    if ((rc = raster_all(&sc, &g)))
        goto done;
    scene_hash(&sc, hash);
    if (samples_build(g, sc.views, sc.nviews, use, hash, &s, &e)) {
        rc = fail_err(&e);
        goto done;
    }
    if (dir) {
        rgb = malloc((size_t)3 * s.n * sizeof *rgb);
        if (!rgb || samples_gather(&s, imgs, rgb, &e)) {
            rc = rgb ? fail_err(&e) : fail(1, "out of memory");
            goto done;
        }
    }
    if (samples_export(&s, rgb, channel, out, &e)) {
        rc = fail_err(&e);
        goto done;
    }
    printf("%d samples -> %s\n", s.n, out);
done:
    free(rgb);
    samples_free(&s);
    free_imgs(imgs, sc.nviews);
    free(use);
    raster_free_all(g, sc.nviews);
    scene_free(&sc);
    return rc;
}

static int cmd_fit_samples(int argc, char **argv)
{
    static const struct option lo[] = {{"out", required_argument, 0, 'o'},
                                       {"eval", required_argument, 0, 'e'},
                                       {"eval-out", required_argument, 0, 'x'},
                                       FIT_LONGOPTS,
                                       {0, 0, 0, 0}};
    fit_opts o;
    const char *out = NULL, *eval = NULL, *eval_out = NULL;
    int c, rc = 0;
    samples s;
    float *vals = NULL;
    fit_prep fp;
    material m;
    glint_err e;

    memset(&fp, 0, sizeof fp);
    memset(&m, 0, sizeof m);
    fit_opts_default(&o);
    optind = 1;
    while ((c = getopt_long(argc, argv, "o:", lo, NULL)) != -1) {
        if (c == 'o') out = optarg;
        else if (c == 'e') eval = optarg;
        else if (c == 'x') eval_out = optarg;
        else if ((rc = fit_opt(&o, c, optarg)) != 0)
            return rc > 0 ? rc : fail(1, "usage: glint fit-samples samples.txt -o MATDIR [--eval samples.txt --eval-out values.txt] [fit options]");
    }
    if (!out || optind != argc - 1)
        return fail(1, "usage: glint fit-samples samples.txt -o MATDIR [--eval samples.txt --eval-out values.txt] [fit options]");
    if (samples_import(argv[optind], &s, &vals, &e))
        return fail_err(&e);
    if (fit_prepare_samples(&fp, &s, &o.p, o.cache_dir, &e) || fit_run(&fp, NULL, vals, &m, &e)) {
        rc = fail_err(&e);
        goto done;
    }
    if ((rc = save_material(&m, out)))
        goto done;
    if (eval) {
        samples es;
        float *ev = NULL;
        double ss = 0, mx = 0;
        FILE *fo = NULL;
        if (samples_import(eval, &es, &ev, &e)) {
            rc = fail_err(&e);
            goto done;
        }
        if (eval_out && !(fo = fopen(eval_out, "w"))) {
            rc = fail(2, "cannot write %s: %s", eval_out, strerror(errno));
            samples_free(&es);
            free(ev);
            goto done;
        }
        for (int i = 0; i < es.n; i++) {
            double n[3], wi[3], wo[3], rgb[3], d;
            for (int k = 0; k < 3; k++) {
                n[k] = es.nrm[3 * i + k]; wi[k] = es.wi[3 * i + k]; wo[k] = es.wo[3 * i + k];
            }
            material_eval(&m, n, wi, wo, rgb);
            d = rgb[0] - ev[3 * i];
            ss += d * d;
            if (fabs(d) > mx) mx = fabs(d);
            if (fo) fprintf(fo, "%.17g\n", rgb[0]);
        }
        if (fo) fclose(fo);
        json_object_set_new(m.info, "eval", json_pack("{s:s, s:i, s:f, s:f}", "file", eval, "samples",
                                                     es.n, "rms", sqrt(ss / es.n), "max_abs", mx));
        samples_free(&es);
        free(ev);
    }
    print_json(m.info);
done:
    material_free(&m);
    fit_prep_free(&fp);
    samples_free(&s);
    free(vals);
    return rc;
}

/* ---- demo ---------------------------------------------------------------------- */

static int cmd_demo(int argc, char **argv)
{
    const char *out = argc > 2 && strcmp(argv[1], "-o") == 0 ? argv[2] : "glint-demo";
    const char *spec = "ct:rough=0.3,kd=0.6/0.35/0.2,f0=0.04";
    scene_params sp;
    scene train, novel;
    gbuf *gt = NULL, *gn = NULL;
    img *pt = NULL, *pn = NULL;
    brdf b;
    fit_params p;
    fit_prep fp;
    material m;
    glint_err e;
    double scale = 0, rms_n = 0, max_n = 0;
    char path[4096];
    int rc = 0;

    if (argc > 1 && !(argc == 3 && strcmp(argv[1], "-o") == 0))
        return fail(1, "usage: glint demo [-o DIR]");
    memset(&fp, 0, sizeof fp);
    memset(&m, 0, sizeof m);
    memset(&train, 0, sizeof train);
    memset(&novel, 0, sizeof novel);
    scene_params_default(&sp);
    if (brdf_parse(spec, &b, &e) || scene_create(&sp, &train, &e) || fsio_mkdirs(out, &e)) {
        rc = fail_err(&e);
        goto done;
    }
    sp.view_set = SCENE_VIEWS_ICO20;
    sp.light_mid = 1;
    if (scene_create(&sp, &novel, &e) || raster_scene(&train, &gt, &e) ||
        raster_scene(&novel, &gn, &e)) {
        rc = fail_err(&e);
        goto done;
    }
    pt = calloc((size_t)train.nviews, sizeof *pt);
    pn = calloc((size_t)novel.nviews, sizeof *pn);
    if (!pt || !pn) {
        rc = fail(1, "out of memory");
        goto done;
    }
    printf("glint demo: painting the built-in sphere from %d views with %s\n", train.nviews, spec);
    if (paint_views(&b, gt, train.views, train.nviews, 0.0, pt, &scale, &e) ||
        paint_views(&b, gn, novel.views, novel.nviews, scale, pn, NULL, &e)) {
        rc = fail_err(&e);
        goto done;
    }
    snprintf(path, sizeof path, "%s/scene.json", out);
    if (scene_save(&train, path, &e)) {
        rc = fail_err(&e);
        goto done;
    }
    snprintf(path, sizeof path, "%s/paintings", out);
    if (fsio_mkdirs(path, &e)) {
        rc = fail_err(&e);
        goto done;
    }
    for (int v = 0; v < train.nviews; v++) {
        snprintf(path, sizeof path, "%s/paintings/view_%02d.png", out, v);
        if (img_write(path, &pt[v], &e)) {
            rc = fail_err(&e);
            goto done;
        }
    }
    fit_params_default(&p);
    if (fit_prepare(&fp, &train, gt, NULL, &p, default_cache_dir(), &e) ||
        fit_run(&fp, pt, NULL, &m, &e)) {
        rc = fail_err(&e);
        goto done;
    }
    if (fit_error_views(&m, gn, novel.views, novel.nviews, pn, &rms_n, &max_n, NULL, &e)) {
        rc = fail_err(&e);
        goto done;
    }
    json_object_set_new(m.info, "novel_views",
                        json_pack("{s:i, s:f, s:f}", "views", novel.nviews, "rms", rms_n,
                                  "max_abs", max_n));
    snprintf(path, sizeof path, "%s/material", out);
    if ((rc = save_material(&m, path)))
        goto done;
    for (int v = 0; v < 4; v++) {
        img im = {0};
        snprintf(path, sizeof path, "%s/render_novel_%02d.png", out, v);
        if (material_shade(&m, &gn[v], novel.views[v].light_intensity, 0.0f, &im, &e) ||
            img_write(path, &im, &e)) {
            img_free(&im);
            rc = fail_err(&e);
            goto done;
        }
        img_free(&im);
    }
    {
        json_t *j = json_object_get(m.info, "errors"), *s = json_object_get(m.info, "seconds");
        printf("  %d samples, %d texels per factor, precomputation %.3f s (%s), fit %.3f ms\n",
               fp.s.n, p.res, fp.t_decomp + fp.t_op,
               fp.cache_hit == 1 ? "loaded from cache" : "computed",
               1e3 * json_real_value(json_object_get(s, "fit")));
        printf("  RMS on painted pixels %.4f, on %d novel views %.4f (max %.3f)\n",
               json_real_value(json_object_get(j, "rms_painted")), novel.nviews, rms_n, max_n);
        printf("  wrote %s/material (factors.exr, factors.png, material.json), %s/paintings, "
               "%s/render_novel_*.png\n", out, out, out);
    }
done:
    material_free(&m);
    fit_prep_free(&fp);
    free_imgs(pt, train.nviews);
    free_imgs(pn, novel.nviews);
    raster_free_all(gt, train.nviews);
    raster_free_all(gn, novel.nviews);
    scene_free(&train);
    scene_free(&novel);
    return rc;
}

/* ---- main ---------------------------------------------------------------------- */

static void usage(FILE *f)
{
    fputs("glint " GLINT_VERSION ": paint how an object should look; glint finds the BRDF.\n"
          "\n"
          "usage: glint COMMAND [ARGS]\n"
          "  scene create [--mesh sphere|torus|teapot|FILE] [--size N|WxH] [--views ico12|ico20]\n"
          "               [--light-angles LO:HI[:mid]] [--distance D] -o scene.json\n"
          "  scene show scene.json               describe a scene (hash, views, samples)\n"
          "  gbuffer scene.json -o DIR [--view K] G-buffers as OpenEXR (named channels)\n"
          "  paint scene.json --brdf SPEC -o DIR [--scale S] [--format exr|png|hdr]\n"
          "                                      paint every view with an analytic BRDF\n"
          "                                      (lambert, phong, blinn, ct, ward; e.g.\n"
          "                                      'ct:rough=0.2,kd=0.5,f0=0.3')\n"
          "  fit scene.json (--paintings DIR | FILE...) -o MATDIR [fit options]\n"
          "  base-render scene.json -o DIR [--brdf SPEC] [--scale S] [--engine E]\n"
          "                                      the images an artist paints over\n"
          "  render MATDIR --scene scene.json (--view K | --eye X,Y,Z --light X,Y,Z\n"
          "         [--target X,Y,Z] [--fov DEG]) [--intensity I] [--size WxH]\n"
          "         [--engine auto|egl|cpu] -o IMAGE   (auto: EGL if it works, else CPU)\n"
          "  export-shader MATDIR -o DIR         GLSL + factor texture + binding manifest\n"
          "  eval MATDIR --dirs FILE [-o OUT]    evaluate at direction pairs\n"
          "  export-samples scene.json [--paintings DIR] [--channel C] -o samples.txt\n"
          "  fit-samples samples.txt -o MATDIR [--eval samples.txt [--eval-out F]] [fit options]\n"
          "  demo [-o DIR]                       paint the sphere, fit, render new views\n"
          "  version | help\n"
          "\n"
          "fit options:\n"
          "  --res R            texels per factor, 4..512 (128)\n"
          "  --lambda L         Laplacian smoothing weight (0.1)\n"
          "  --reg SPEC         trunc[:full|:K|:P%|:relT], tikhonov:A|:relT, linear[:K|:P%]\n"
          "                     (trunc:full)\n"
          "  --map SPEC         log | add[:a] | sub[:margin], optional ',eps=E' (add:0.1)\n"
          "  --model M          radiance | brdf (radiance)\n"
          "  --precision P      double | single operator (double)\n"
          "  --route R          eig (B^T B eigendecomposition) | svd (dense gesdd) (eig)\n"
          "  --rcond T          relative singular-value cutoff (1e-6)\n"
          "  --cache-dir DIR    precomputation cache ($XDG_CACHE_HOME/glint); --no-cache\n",
          f);
}

int main(int argc, char **argv)
{
    static const struct { const char *name; int (*fn)(int, char **); } cmds[] = {
        {"scene", cmd_scene}, {"gbuffer", cmd_gbuffer}, {"paint", cmd_paint},
        {"fit", cmd_fit}, {"render", cmd_render}, {"eval", cmd_eval},
        {"export-samples", cmd_export_samples}, {"fit-samples", cmd_fit_samples},
        {"demo", cmd_demo}, {"base-render", cmd_base_render},
        {"export-shader", cmd_export_shader}};
    static char name[64];

    if (argc < 2 || strcmp(argv[1], "help") == 0 || strcmp(argv[1], "--help") == 0 ||
        strcmp(argv[1], "-h") == 0) {
        usage(argc < 2 ? stderr : stdout);
        return argc < 2 ? 1 : 0;
    }
    if (strcmp(argv[1], "version") == 0 || strcmp(argv[1], "--version") == 0) {
        puts("glint " GLINT_VERSION);
        return 0;
    }
    for (unsigned i = 0; i < sizeof cmds / sizeof cmds[0]; i++) {
        if (strcmp(argv[1], cmds[i].name) == 0) {
            snprintf(name, sizeof name, "glint %s", cmds[i].name);
            cmd_name = name;
            {
                int rc = cmds[i].fn(argc - 1, argv + 1);
                gl_release();
                return rc;
            }
        }
    }
    fprintf(stderr, "glint: unknown command '%s' (try 'glint help')\n", argv[1]);
    return 1;
}
