/* cmd_fit.c: the glint commands that fit a material: fit (paintings of a
 * scene), export-samples and fit-samples (samples in a text file, e.g. to
 * compare with the reference), fit-gbuffers (G-buffers and paintings made
 * elsewhere).  Fits go through the method's levels and the
 * cache on disk (prep.h, cache.h), as in the daemon. */
#include <errno.h>
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <sys/stat.h>

#include "cli.h"
#include "gbfit.h"
#include "gbuf.h"
#include "prep.h"
#include "raster.h"
#include "samples.h"

/* ---- fit -------------------------------------------------------------------- */

static int borrowed_scene(void *cls, const char *id, const scene **out, glint_err *err)
{
    (void)id;
    (void)err;
    *out = cls;
    return 0;
}

/* Fit the paintings of the views flagged in `use` with the options'
 * method.  OUT: *m. */
int cli_fit_scene(const fit_opts *o, const scene *sc, const unsigned char *use, const img *imgs,
                  material *m)
{
    prep_scene_source src = {borrowed_scene, NULL, (void *)sc};
    cache *c = NULL;
    cache_entry *se = NULL;
    prep *p = NULL;
    glint_err e;
    int rc;

    memset(m, 0, sizeof *m);
    if ((rc = cache_open(o->cache_dir, 0, &c, &e)) ||
        (rc = prep_scene_acquire(c, "cli", &src, &se, &e)))
        goto done;
    {
        prep_request rq = {o->m, o->params, se, use, NULL};
        if ((rc = prep_acquire(c, &rq, NULL, NULL, &p, &e)) ||
            (rc = prep_fit(p, imgs, NULL, m, &e)))
            goto done;
    }
done:
    prep_release(c, p);
    cache_release(c, se);
    cache_close(c);
    return rc ? fail_err(&e) : 0;
}

static const char usage_fit[] =
    "usage: glint fit scene.json (--paintings DIR | FILE...) -o MATDIR [fit options]";

int cmd_fit(int argc, char **argv)
{
    static const struct option own[] = {{"paintings", required_argument, 0, 'p'},
                                        {"out", required_argument, 0, 'o'},
                                        {"quiet", no_argument, 0, 'q'}};
    struct option *lo = fit_opts_table(own, 3);
    fit_opts o;
    const char *dir = NULL, *out = NULL, *scene_path;
    int c, rc = 0, quiet = 0;
    scene sc;
    img *imgs = NULL;
    unsigned char *use = NULL;
    material m;

    memset(&sc, 0, sizeof sc);
    memset(&m, 0, sizeof m);
    fit_opts_init(&o);
    if (!lo)
        return fail(1, "out of memory");
    optind = 1;
    while ((c = getopt_long(argc, argv, "p:o:q", lo, NULL)) != -1) {
        if (c == 'p') dir = optarg;
        else if (c == 'o') out = optarg;
        else if (c == 'q') quiet = 1;
        else if ((rc = fit_opt(&o, c, optarg)) != 0) {
            free(lo);
            return rc > 0 ? rc : fail(1, "%s", usage_fit);
        }
    }
    free(lo);
    if (!out || optind >= argc)
        return fail(1, "%s", usage_fit);
    if ((rc = fit_opts_resolve(&o)))
        goto done;
    scene_path = argv[optind++];
    if ((rc = load_scene(scene_path, &sc)))
        goto done;
    imgs = calloc((size_t)sc.nviews, sizeof *imgs);
    use = calloc((size_t)sc.nviews, 1);
    if (!imgs || !use) {
        rc = fail(1, "out of memory");
        goto done;
    }
    if ((rc = read_paintings(&sc, dir, argv + optind, argc - optind, imgs, use)) ||
        (rc = cli_fit_scene(&o, &sc, use, imgs, &m)))
        goto done;
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
    fit_opts_free(&o);
    free_imgs(imgs, sc.nviews);
    free(use);
    scene_free(&sc);
    return rc;
}

/* ---- samples export / fit --------------------------------------------------- */

int cmd_export_samples(int argc, char **argv)
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

/* The error of m on the samples of a file (first channel), optionally
 * writing each value to eval_out; adds info.eval. */
static int eval_samples(material *m, const char *eval, const char *eval_out)
{
    samples es;
    float *ev = NULL;
    double ss = 0, mx = 0;
    FILE *fo = NULL;
    glint_err e;

    if (samples_import(eval, &es, &ev, &e))
        return fail_err(&e);
    if (eval_out && !(fo = fopen(eval_out, "w"))) {
        int rc = fail(2, "cannot write %s: %s", eval_out, strerror(errno));
        samples_free(&es);
        free(ev);
        return rc;
    }
    for (int i = 0; i < es.n; i++) {
        double n[3], wi[3], wo[3], rgb[3], d, uv[2] = {0.0, 0.0};
        for (int k = 0; k < 3; k++) {
            n[k] = es.nrm[3 * i + k];
            wi[k] = es.wi[3 * i + k];
            wo[k] = es.wo[3 * i + k];
        }
        if (es.uv) {
            uv[0] = es.uv[2 * (size_t)i];
            uv[1] = es.uv[2 * (size_t)i + 1];
        }
        material_eval_at(m, es.uv ? uv : NULL, n, wi, wo, rgb);
        d = rgb[0] - ev[3 * i];
        ss += d * d;
        if (fabs(d) > mx)
            mx = fabs(d);
        if (fo)
            fprintf(fo, "%.17g\n", rgb[0]);
    }
    if (fo)
        fclose(fo);
    json_object_set_new(m->info, "eval", json_pack("{s:s, s:i, s:f, s:f}", "file", eval,
                                                   "samples", es.n, "rms", sqrt(ss / es.n),
                                                   "max_abs", mx));
    samples_free(&es);
    free(ev);
    return 0;
}

static const char usage_fit_samples[] =
    "usage: glint fit-samples samples.txt -o MATDIR [--eval samples.txt --eval-out values.txt] "
    "[fit options]";

int cmd_fit_samples(int argc, char **argv)
{
    static const struct option own[] = {{"out", required_argument, 0, 'o'},
                                        {"eval", required_argument, 0, 'e'},
                                        {"eval-out", required_argument, 0, 'x'}};
    struct option *lo = fit_opts_table(own, 3);
    fit_opts o;
    const char *out = NULL, *eval = NULL, *eval_out = NULL;
    int c, rc = 0;
    samples s;
    float *vals = NULL;
    cache *cc = NULL;
    prep *p = NULL;
    material m;
    glint_err e;

    memset(&s, 0, sizeof s);
    memset(&m, 0, sizeof m);
    fit_opts_init(&o);
    if (!lo)
        return fail(1, "out of memory");
    optind = 1;
    while ((c = getopt_long(argc, argv, "o:", lo, NULL)) != -1) {
        if (c == 'o') out = optarg;
        else if (c == 'e') eval = optarg;
        else if (c == 'x') eval_out = optarg;
        else if ((rc = fit_opt(&o, c, optarg)) != 0) {
            free(lo);
            return rc > 0 ? rc : fail(1, "%s", usage_fit_samples);
        }
    }
    free(lo);
    if (!out || optind != argc - 1)
        return fail(1, "%s", usage_fit_samples);
    if ((rc = fit_opts_resolve(&o)))
        goto done;
    if (samples_import(argv[optind], &s, &vals, &e)) {
        rc = fail_err(&e);
        goto done;
    }
    if (cache_open(o.cache_dir, 0, &cc, &e) ||
        prep_acquire_samples(cc, o.m, o.params, &s, NULL, NULL, NULL, &p, &e) ||
        prep_fit(p, NULL, vals, &m, &e)) {
        rc = fail_err(&e);
        goto done;
    }
    if ((rc = save_material(&m, out)) || (eval && (rc = eval_samples(&m, eval, eval_out))))
        goto done;
    print_json(m.info);
done:
    prep_release(cc, p);
    cache_close(cc);
    material_free(&m);
    fit_opts_free(&o);
    samples_free(&s);
    free(vals);
    return rc;
}

/* ---- fit-gbuffers: G-buffers and paintings made elsewhere ----------------------------- */

static const char usage_fit_gbuffers[] =
    "usage: glint fit-gbuffers GBDIR --paintings DIR -o MATDIR [fit options]\n"
    "  GBDIR/view_00.exr, view_01.exr, ...: G-buffers with named channels N.X N.Y N.Z,\n"
    "  wo.X wo.Y wo.Z (towards the camera) and, for point-light methods, wi.X wi.Y wi.Z\n"
    "  (towards the light); mask, P.X P.Y P.Z, uv.U uv.V optional (what glint gbuffer\n"
    "  writes); DIR/view_KK.exr|hdr|png: the RGB paintings of those views (views\n"
    "  without one are not used), per unit light.  Every method: those that vary over\n"
    "  the surface need uv; srbf fits paintings lit by its --env (a built-in or\n"
    "  file:PATH) and, without the scene's mesh, models no occlusion (visibility off).";

/* The G-buffers GBDIR/view_KK.exr while they exist (OUT: g[*n], *has_uv). */
static int read_gbuffers(const method *m, const char *dir, gbuf *g, int *n, int *has_uv)
{
    char path[4096];
    glint_err e;

    *has_uv = 1;
    for (*n = 0; *n < SCENE_MAX_VIEWS; (*n)++) {
        struct stat st;
        int uv = 0, wi = 0, k = *n;
        snprintf(path, sizeof path, "%s/view_%02d.exr", dir, k);
        if (stat(path, &st))
            break;
        if (gbfit_gbuf_file(m, path, &g[k], &uv, &wi, &e))
            return fail_err(&e);
        if (k > 0 && (g[k].width != g[0].width || g[k].height != g[0].height))
            return fail(1, "%s is %dx%d but view 0's G-buffer is %dx%d", path, g[k].width,
                        g[k].height, g[0].width, g[0].height);
        *has_uv &= uv;
    }
    if (*n == 0)
        return fail(1, "no G-buffer in %s (expected view_00.exr, view_01.exr, ...)", dir);
    return 0;
}

int cmd_fit_gbuffers(int argc, char **argv)
{
    static const struct option own[] = {{"out", required_argument, 0, 'o'},
                                        {"paintings", required_argument, 0, 'p'}};
    struct option *lo = fit_opts_table(own, 2);
    gbuf g[SCENE_MAX_VIEWS];
    img imgs[SCENE_MAX_VIEWS];
    unsigned char use[SCENE_MAX_VIEWS];
    const char *out = NULL, *pdir = NULL;
    char path[4096];
    int c, rc = 0, n = 0, has_uv = 1, found = 0;
    fit_opts o;
    samples s;
    float *vals = NULL;
    cache *cc = NULL;
    prep *p = NULL;
    material m;
    glint_err e;

    memset(g, 0, sizeof g);
    memset(imgs, 0, sizeof imgs);
    memset(use, 0, sizeof use);
    memset(&s, 0, sizeof s);
    memset(&m, 0, sizeof m);
    fit_opts_init(&o);
    if (!lo)
        return fail(1, "out of memory");
    optind = 1;
    while ((c = getopt_long(argc, argv, "o:p:", lo, NULL)) != -1) {
        if (c == 'o') out = optarg;
        else if (c == 'p') pdir = optarg;
        else if ((rc = fit_opt(&o, c, optarg)) != 0) {
            free(lo);
            return rc > 0 ? rc : fail(1, "%s", usage_fit_gbuffers);
        }
    }
    free(lo);
    if (!out || !pdir || optind != argc - 1)
        return fail(1, "%s", usage_fit_gbuffers);
    if ((rc = fit_opts_resolve(&o)) || (rc = read_gbuffers(o.m, argv[optind], g, &n, &has_uv)))
        goto done;
    for (int v = 0; v < n; v++) {
        use[v] = find_painting(pdir, v, path, sizeof path);
        if (!use[v])
            continue;
        if (img_read(path, &imgs[v], &e)) {
            glint_err_prefix(&e, "painting of view %d (%s)", v, path);
            rc = fail_err(&e);
            goto done;
        }
        found++;
    }
    if (!found) {
        rc = fail(1, "no painting in %s for the %d G-buffers (expected view_00.exr, ...)", pdir,
                  n);
        goto done;
    }
    if (gbfit_samples(o.m, g, imgs, use, n, has_uv, &s, &vals, &e) ||
        cache_open(o.cache_dir, 0, &cc, &e) ||
        prep_acquire_samples(cc, o.m, o.params, &s, NULL, NULL, NULL, &p, &e) ||
        prep_fit(p, NULL, vals, &m, &e)) {
        rc = fail_err(&e);
        goto done;
    }
    if ((rc = save_material(&m, out)))
        goto done;
    print_json(m.info);
done:
    prep_release(cc, p);
    cache_close(cc);
    material_free(&m);
    fit_opts_free(&o);
    samples_free(&s);
    free(vals);
    for (int v = 0; v < SCENE_MAX_VIEWS; v++) {
        gbuf_free(&g[v]);
        img_free(&imgs[v]);
    }
    return rc;
}
