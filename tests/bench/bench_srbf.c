/* bench_srbf.c: the environment-lit method (srbf) beside seed 004's Table 1,
 * and its speed-accuracy table.
 *
 *   bench_srbf [--quick] [--data DIR] [--table1] [--mesh NAME] [--env NAME]
 *              [--vis on|off] [--reps N]
 *
 * --table1: Table 1 only; --mesh NAME: only that mesh's rows (sphere,
 * bunny.ply, cow.off); --env, --vis: only the rows of that environment
 * (a substring of its name) or visibility; --reps: fits per row.
 *
 * Table 1: for the sphere, the bunny and the cow at 160x120 (one painted
 * view), under two CC0 environments (DIR/envmaps: courtyard.exr and
 * sunset.exr; the built-in "sky" and "studio" when absent), with and
 * without visibility: pixels (rows), T_trans (visibility + transfer
 * matrices + Gram matrices, cold), T_s (a fit with T'T cached, the solver
 * started at zero: T'b and three constrained solves), and of the slowest
 * of the three channels (run on threads): its whole time (T'b, the solve,
 * the report), the solver's alone and its active-set steps; then repaints:
 * a stroke (a tenth of the rows 30% brighter) and back, the solver started
 * at zero (start cold, the default) and from the other's answer (start
 * warm), best and median, and the most steps of a channel.  Each T_s fit
 * paints the whole view anew (T'b reads every row); a repaint's T'b reads
 * the rows the stroke changed.
 *
 * Speed-accuracy: a Cook-Torrance GGX 0.3 target on the sphere fitted from
 * one view, measured on a new view with the environment rotated by 120
 * degrees (relative RMS), against lights, basis resolution, fit grid and
 * constraints, with the fit and precomputation times.  Truths are rendered
 * with the lights of 1024-light median cut of the same map, so the error
 * includes the compression's.
 *
 * Nothing here is asserted; the figures go to BENCHMARKS.md. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "bench_env.h"
#include "brdf.h"
#include "cache.h"
#include "clock.h"
#include "env.h"
#include "material.h"
#include "method_srbf.h"
#include "prep.h"
#include "samples.h"
#include "scene.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

static int make_scene(const char *mesh_file, scene *sc, glint_err *e)
{
    scene_params p;
    scene_params_default(&p);
    p.width = 160;
    p.height = 120;
    if (strcmp(mesh_file, "sphere")) {
        char path[1200];
        struct stat st;
        snprintf(path, sizeof path, "%s/meshes/%s", DATA, mesh_file);
        if (stat(path, &st))
            return glint_err_set(e, GLINT_ENOTFOUND, "%s absent", path);
        snprintf(p.mesh_path, sizeof p.mesh_path, "%s", path);
    }
    return scene_create(&p, sc, e);
}

/* Render the samples of s under lights l with BRDF b (f cos summed). */
static void render_brdf(const samples *s, const env_lights *l, const brdf *b, float *rgb)
{
    for (int i = 0; i < s->n; i++) {
        double n[3], wo[3], acc[3] = {0, 0, 0};
        for (int e = 0; e < 3; e++) {
            n[e] = s->nrm[3 * i + e];
            wo[e] = s->wo[3 * i + e];
        }
        for (int k = 0; k < l->k; k++) {
            const double *d = l->dir + 3 * k;
            double cs = n[0] * d[0] + n[1] * d[1] + n[2] * d[2], v[3];
            if (cs <= 0.0)
                continue;
            brdf_eval(b, n, d, wo, v);
            for (int c = 0; c < 3; c++)
                acc[c] += l->power[3 * k + c] * v[c] * cs;
        }
        for (int c = 0; c < 3; c++)
            rgb[3 * i + c] = (float)acc[c];
    }
}

static void render_mat(const samples *s, const env_lights *l, const srbf_material *m, float *rgb)
{
    for (int i = 0; i < s->n; i++) {
        double n[3], wo[3], acc[3] = {0, 0, 0};
        for (int e = 0; e < 3; e++) {
            n[e] = s->nrm[3 * i + e];
            wo[e] = s->wo[3 * i + e];
        }
        for (int k = 0; k < l->k; k++) {
            const double *d = l->dir + 3 * k;
            double cs = n[0] * d[0] + n[1] * d[1] + n[2] * d[2], v[3];
            if (cs <= 0.0)
                continue;
            srbf_material_eval(m, n, d, wo, v);
            for (int c = 0; c < 3; c++)
                acc[c] += l->power[3 * k + c] * v[c] * cs;
        }
        for (int c = 0; c < 3; c++)
            rgb[3 * i + c] = (float)acc[c];
    }
}

static double seconds_of(const material *m, const char *what)
{
    return json_real_value(json_object_get(json_object_get(m->info, "seconds"), what));
}

/* The slowest channel's seconds (with its T'f), solve seconds and steps. */
static void chan_figures(const material *m, double *sv, double *sl, int *its)
{
    const json_t *ch = json_object_get(json_object_get(m->info, "errors"), "channels");
    for (size_t i = 0; i < json_array_size(ch); i++) {
        const json_t *ci = json_array_get(ch, i);
        *sv = fmax(*sv, json_real_value(json_object_get(ci, "seconds")));
        *sl = fmax(*sl, json_real_value(json_object_get(ci, "solve_seconds")));
        *its = (int)fmax(*its, json_integer_value(json_object_get(ci, "iterations")));
    }
}

static int dcmp(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* One cold precomputation, fits of view 0 from zero (T_s) and repaints
 * warm from the previous answer. */
static int table1_row(const char *mesh_file, const char *env, int vis, int reps)
{
    scene sc;
    cache *c = NULL;
    cache_entry *se = NULL;
    prep *p = NULL;
    srbf_params par;
    unsigned char use[SCENE_MAX_VIEWS] = {1};
    brdf b;
    env_lights l;
    material m;
    glint_err e;
    double t0, t_prep, best = 1e30, solve = 1e30, solver = 0.0, rel = 0.0;
    double ts_all[64];
    int iters = 0, nts = 0;
    float *rgb;
    const samples *s;
    prep_scene_source src = {borrowed, NULL, &sc};

    memset(&sc, 0, sizeof sc);
    memset(&l, 0, sizeof l);
    if (make_scene(mesh_file, &sc, &e)) {
        printf("| %s | %s | %s | skipped: %s |\n", mesh_file, env, vis ? "on" : "off", e.msg);
        return 0;
    }
    method_srbf.params_default(&par);
    snprintf(par.env, sizeof par.env, "%.63s", env);
    par.visibility = vis ? SRBF_VIS_ON : SRBF_VIS_OFF;
    par.start = SRBF_START_COLD; /* T_s: each fit from zero */
    brdf_parse("ct:rough=0.3,kd=0.35/0.25/0.15,f0=0.25", &b, &e);
    cache_open(NULL, (size_t)4 << 30, &c, &e);
    prep_scene_acquire(c, mesh_file, &src, &se, &e);
    {
        prep_request rq = {&method_srbf, &par, se, use, NULL};
        t0 = glint_now();
        if (prep_acquire(c, &rq, NULL, NULL, &p, &e)) {
            printf("| %s | %s | %s | failed: %s |\n", mesh_file, env, vis ? "on" : "off", e.msg);
            goto done;
        }
        t_prep = glint_now() - t0;
    }
    s = prep_samples(p);
    rgb = malloc((size_t)3 * s->n * sizeof *rgb);
    lights_of(env, 256, 0.0, &l, &e);
    render_brdf(s, &l, &b, rgb);
    float *rgbr = malloc((size_t)3 * s->n * sizeof *rgbr);
    for (int r = 0; r < reps; r++) {
        double sv = 0.0, sl = 0.0;
        int its = 0;
        /* a new painting each time (every row changes, so T'b is a full
         * pass, not an update from the kept painting) */
        for (long i = 0; i < 3 * (long)s->n; i++)
            rgbr[i] = rgb[i] * (1.0f + (float)r / 1024.0f);
        t0 = glint_now();
        if (prep_fit(p, NULL, rgbr, &m, &e)) {
            printf("fit failed: %s\n", e.msg);
            break;
        }
        t0 = glint_now() - t0;
        best = t0 < best ? t0 : best;
        if (nts < 64)
            ts_all[nts++] = t0;
        chan_figures(&m, &sv, &sl, &its);
        if (sv < solve) {
            solve = sv;
            solver = sl;
            iters = its;
        }
        if (r == reps - 1) {
            const json_t *pre = json_object_get(m.info, "precomputation");
            qsort(ts_all, (size_t)nts, sizeof *ts_all, dcmp);
            printf("| %s | %s | %s | %lld | %d/%d | %.3f | %.3f | %.3f | %.2f / %.2f | %.2f | %.2f "
                   "| %d ",
                   mesh_file, env, vis ? "on" : "off",
                   (long long)json_integer_value(json_object_get(pre, "rows")),
                   (int)json_integer_value(json_object_get(pre, "lobes_reached")),
                   (int)json_integer_value(json_object_get(pre, "lobes")),
                   seconds_of(&m, "visibility"), seconds_of(&m, "transfer") +
                   seconds_of(&m, "gram"), t_prep, best * 1e3, ts_all[nts / 2] * 1e3,
                   solve * 1e3, solver * 1e3, iters);
            rel = json_real_value(json_object_get(json_object_get(m.info, "errors"),
                                                  "rel_rms_painted"));
        }
        material_free(&m);
    }
    free(rgbr);
    /* repaints: a stroke (a band of a tenth of the rows painted 30%
     * brighter) and back, the solver started at zero (the default) and then
     * warm from the other's answer; T'b reads the stroke's rows either way */
    for (int mode = 0; mode < 2; mode++) {
        srbf_params pw = par;
        prep *p2 = NULL;
        float *rgb2 = malloc((size_t)3 * s->n * sizeof *rgb2);
        double tw[2 * 10 + 2];
        int nw = 0, wits = 0;
        pw.start = mode ? SRBF_START_WARM : SRBF_START_COLD;
        prep_request rq = {&method_srbf, &pw, se, use, NULL};
        memcpy(rgb2, rgb, (size_t)3 * s->n * sizeof *rgb2);
        for (long i = s->n / 3; i < s->n / 3 + s->n / 10; i++)
            for (int k = 0; k < 3; k++)
                rgb2[3 * i + k] *= 1.3f;
        if (!prep_acquire(c, &rq, NULL, NULL, &p2, &e) && !prep_fit(p2, NULL, rgb, &m, &e)) {
            material_free(&m);
            for (int r = 0; r < 2 * reps && r < 2 * 10 + 2; r++) {
                double sv = 0, sl = 0;
                int its = 0;
                t0 = glint_now();
                if (prep_fit(p2, NULL, r % 2 ? rgb : rgb2, &m, &e))
                    break;
                tw[nw++] = glint_now() - t0;
                chan_figures(&m, &sv, &sl, &its);
                wits = its > wits ? its : wits;
                material_free(&m);
            }
        }
        qsort(tw, (size_t)nw, sizeof *tw, dcmp);
        if (nw)
            printf("| %.2f / %.2f | %d ", tw[0] * 1e3, tw[nw / 2] * 1e3, wits);
        else
            printf("| failed: %s | ", e.msg);
        prep_release(c, p2);
        free(rgb2);
    }
    printf("| %.4f |\n", rel);
    free(rgb);
done:
    env_lights_free(&l);
    prep_release(c, p);
    cache_release(c, se);
    cache_close(c);
    scene_free(&sc);
    return 0;
}

/* The speed-accuracy table on the sphere. */
static void accuracy_row(scene *sc, const char *env, const srbf_params *par, const char *label)
{
    cache *c = NULL;
    cache_entry *se = NULL;
    prep *p = NULL, *pn = NULL;
    unsigned char use[SCENE_MAX_VIEWS] = {1}, usen[SCENE_MAX_VIEWS] = {0};
    env_lights l0, lr;
    brdf b;
    material m;
    glint_err e;
    float *rgb, *a, *t;
    const samples *s;
    double t0, t_prep, t_fit, num = 0, den = 0;
    prep_scene_source src = {borrowed, NULL, sc};

    usen[5] = 1;
    memset(&l0, 0, sizeof l0);
    memset(&lr, 0, sizeof lr);
    brdf_parse("ct:rough=0.3,kd=0.35/0.25/0.15,f0=0.25", &b, &e);
    cache_open(NULL, (size_t)4 << 30, &c, &e);
    prep_scene_acquire(c, "s", &src, &se, &e);
    {
        prep_request rq = {&method_srbf, par, se, use, NULL},
                     rn = {&method_srbf, par, se, usen, NULL};
        t0 = glint_now();
        if (prep_acquire(c, &rq, NULL, NULL, &p, &e) || prep_acquire(c, &rn, NULL, NULL, &pn, &e)) {
            printf("| %s | failed: %s |\n", label, e.msg);
            goto done;
        }
        t_prep = glint_now() - t0;
    }
    lights_of(env, 1024, 0.0, &l0, &e);
    lights_of(env, 1024, 120.0, &lr, &e);
    s = prep_samples(p);
    rgb = malloc((size_t)3 * s->n * sizeof *rgb);
    render_brdf(s, &l0, &b, rgb);
    prep_fit(p, NULL, rgb, &m, &e); /* warm the caches */
    material_free(&m);
    t0 = glint_now();
    if (prep_fit(p, NULL, rgb, &m, &e)) {
        printf("| %s | fit failed: %s |\n", label, e.msg);
        free(rgb);
        goto done;
    }
    t_fit = glint_now() - t0;
    free(rgb);
    s = prep_samples(pn);
    a = malloc((size_t)3 * s->n * sizeof *a);
    t = malloc((size_t)3 * s->n * sizeof *t);
    render_mat(s, &lr, srbf_material_of(&m), a);
    render_brdf(s, &lr, &b, t);
    for (int i = 0; i < 3 * s->n; i++) {
        num += ((double)a[i] - t[i]) * ((double)a[i] - t[i]);
        den += (double)t[i] * t[i];
    }
    printf("| %s | %.3f | %.2f | %.4f | %.4f |\n", label, t_prep, t_fit * 1e3,
           json_real_value(json_object_get(json_object_get(m.info, "errors"), "rel_rms_painted")),
           sqrt(num / den));
    free(a);
    free(t);
    material_free(&m);
done:
    env_lights_free(&l0);
    env_lights_free(&lr);
    prep_release(c, p);
    prep_release(c, pn);
    cache_release(c, se);
    cache_close(c);
}

int main(int argc, char **argv)
{
    const char *meshes[] = {"sphere", "bunny.ply", "cow.off"};
    const char *envs[2] = {"data:courtyard.exr", "data:sunset.exr"};
    char envbuf[2][64];
    int quick = 0, only_table1 = 0, reps = 0, only_vis = -1;
    const char *only_mesh = NULL, *only_env = NULL;
    struct stat st;
    char probe[1200];

    bench_env_data_default();
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--quick"))
            quick = 1;
        else if (!strcmp(argv[i], "--data") && i + 1 < argc)
            snprintf(DATA, sizeof DATA, "%s", argv[++i]);
        else if (!strcmp(argv[i], "--table1"))
            only_table1 = 1;
        else if (!strcmp(argv[i], "--mesh") && i + 1 < argc)
            only_mesh = argv[++i];
        else if (!strcmp(argv[i], "--env") && i + 1 < argc)
            only_env = argv[++i];
        else if (!strcmp(argv[i], "--vis") && i + 1 < argc)
            only_vis = !strcmp(argv[++i], "on");
        else if (!strcmp(argv[i], "--reps") && i + 1 < argc && atoi(argv[i + 1]) > 0)
            reps = atoi(argv[++i]);
        else {
            fprintf(stderr, "usage: bench_srbf [--quick] [--data DIR] [--table1] [--mesh NAME] "
                            "[--env NAME] [--vis on|off] [--reps N]\n"
                            "  --mesh, --env, --vis: only the Table 1 rows that match (--env "
                            "matches a substring)\n  --reps: warm fits per row (best of; "
                            "default 10, 3 with --quick)\n");
            return 2;
        }
    }
    env_set_resolver(data_resolver);
    snprintf(probe, sizeof probe, "%s/envmaps/courtyard.exr", DATA);
    if (stat(probe, &st)) {
        envs[0] = "sky";
        envs[1] = "studio";
    }
    for (int k = 0; k < 2; k++)
        snprintf(envbuf[k], sizeof envbuf[k], "%s", envs[k]);

    printf("## srbf beside seed 004 Table 1 (160x120, one view, 256 lights, J = 147)\n\n");
    printf("| mesh | environment | visibility | rows | lobes reached | T_vis s | T_trans s | "
           "cold total s | T_s ms best / median | channel ms | solver ms | steps | repaint ms best / median | "
           "repaint steps | repaint warm ms best / median | warm steps | "
           "rel RMS painted (CT 0.3) |\n");
    printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    for (int mi = 0; mi < 3; mi++)
        for (int ei = 0; ei < 2; ei++)
            for (int v = 0; v < 2; v++) {
                if (mi == 0 && v == 1)
                    continue; /* the sphere is convex */
                if ((only_mesh && strcmp(only_mesh, meshes[mi])) ||
                    (only_env && !strstr(envbuf[ei], only_env)) || (only_vis >= 0 && only_vis != v))
                    continue;
                table1_row(meshes[mi], envbuf[ei], v, reps ? reps : quick ? 3 : 10);
            }
    if (only_table1)
        return 0;

    printf("\n## srbf speed-accuracy (sphere 160x120, CT GGX 0.3 target, %s; error on a new "
           "view with the environment rotated by 120 degrees)\n\n",
           envbuf[0]);
    printf("| setting | cold s | warm fit ms | rel RMS painted | rel RMS new view + rotation |\n");
    printf("|---|---|---|---|---|\n");
    {
        scene sc;
        glint_err e;
        srbf_params base, p;
        char label[64];
        static const int lights[] = {64, 256, 1024};
        static const int res[] = {5, 7, 9};
        static const char *rasters[] = {"80x60", "160x120"};
        static const char *cons[] = {"energy", "nonneg", "none"};
        if (make_scene("sphere", &sc, &e))
            return 1;
        method_srbf.params_default(&base);
        snprintf(base.env, sizeof base.env, "%s", envbuf[0]);
        for (int st2 = 0; st2 < 2; st2++) {
            p = base;
            p.static_term = st2;
            snprintf(label, sizeof label, "static %s (default otherwise)", st2 ? "smith" : "paper");
            accuracy_row(&sc, envbuf[0], &p, label);
        }
        base.static_term = SRBF_STATIC_SMITH;
        for (size_t i = 0; i < 3; i++) {
            p = base;
            p.lights = lights[i];
            snprintf(label, sizeof label, "smith, lights %d", lights[i]);
            accuracy_row(&sc, envbuf[0], &p, label);
        }
        for (size_t i = 0; i < 3; i++) {
            p = base;
            p.basis_res = res[i];
            snprintf(label, sizeof label, "smith, basis_res %d (J = %d)", res[i],
                     3 * res[i] * res[i]);
            accuracy_row(&sc, envbuf[0], &p, label);
        }
        for (size_t i = 0; i < 2; i++) {
            glint_err e2;
            p = base;
            method_param_set_text(&method_srbf, &p, "raster", rasters[i], &e2);
            snprintf(label, sizeof label, "smith, raster %s", rasters[i]);
            accuracy_row(&sc, envbuf[0], &p, label);
        }
        for (size_t i = 0; i < 3; i++) {
            p = base;
            p.constraints = (int)i;
            snprintf(label, sizeof label, "smith, constraints %s", cons[i]);
            accuracy_row(&sc, envbuf[0], &p, label);
        }
        if (!quick)
            for (int s2 = 0; s2 < 3; s2++) {
                static const double sm[] = {0.0, 1e-3, 1e-2};
                p = base;
                p.smooth = sm[s2];
                snprintf(label, sizeof label, "smith, smooth %g", sm[s2]);
                accuracy_row(&sc, envbuf[0], &p, label);
            }
        scene_free(&sc);
    }
    return 0;
}
