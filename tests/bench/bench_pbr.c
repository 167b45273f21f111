/* bench_pbr: the pbr method's warm fit (its pbr-geom level in memory) and
 * its errors, side by side, for a few truths.
 *
 *   bench_pbr [--reps N] [--size S] [--measured DIR]
 *
 * The built-in sphere at S x S (default 128), 12 point-lit views (the
 * default scene: lights at 20..70 degrees), painted with each truth (values
 * f ci per unit light at the samples, as a painting gives them).  For each
 * truth and each Fresnel kind: the fit's time (the best of N, default 3;
 * wall clock and this thread's CPU time, which a shared machine inflates
 * less), the final refinement's iterations,
 * its RMS on the 12 painted views' samples (rms_painted) and the RMS on 20
 * new views (the icosahedron's face centres, lights at 5..85 degrees,
 * midpoints), absolute and relative to the truth's RMS there.  The truths:
 * lambert, ct (plastic), ct (metal) and, when DIR (default
 * ../shared/data/measured) holds merl56_fits.json, a handful of sgd:NAME
 * measured materials.  Nothing is asserted: the figures go to
 * BENCHMARKS.md (the floor: a warm fit of 12 views at 128 x 128 in
 * at most 50 ms). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "brdf.h"
#include "clock.h"
#include "material.h"
#include "measured.h"
#include "method_pbr.h"
#include "raster.h"
#include "samples.h"

typedef struct truth {
    const char *spec;
    brdf b;
    measured_truth mt;
    int measured;
} truth;

static void truth_eval(const truth *t, const double n[3], const double wi[3], const double wo[3],
                       double f[3])
{
    if (t->measured)
        measured_eval(&t->mt, n, wi, wo, f);
    else
        brdf_eval(&t->b, n, wi, wo, f);
}

/* This thread's CPU time in seconds (the machine may be shared: wall time
 * counts the other processes too). */
static double cpu_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

static void dirs_of(const samples *s, int i, double n[3], double wi[3], double wo[3])
{
    for (int a = 0; a < 3; a++) {
        n[a] = s->nrm[3 * (size_t)i + a];
        wi[a] = s->wi[3 * (size_t)i + a];
        wo[a] = s->wo[3 * (size_t)i + a];
    }
}

static float *values_of(const truth *t, const samples *s)
{
    float *v = malloc(3 * sizeof(float) * (size_t)s->n);
    for (int i = 0; v && i < s->n; i++) {
        double n[3], wi[3], wo[3], f[3];
        dirs_of(s, i, n, wi, wo);
        truth_eval(t, n, wi, wo, f);
        for (int c = 0; c < 3; c++)
            v[3 * (size_t)i + c] = (float)(f[c] * s->cos_i[i]);
    }
    return v;
}

static int samples_of(const scene_params *sp, samples *s, glint_err *e)
{
    scene sc;
    gbuf *g = NULL;
    char h[33];
    int rc = scene_create(sp, &sc, e) || raster_scene(&sc, &g, e) ||
             (scene_hash(&sc, h), samples_build(g, sc.views, sc.nviews, NULL, h, s, e));
    for (int v = 0; g && v < sc.nviews; v++)
        gbuf_free(&g[v]);
    free(g);
    scene_free(&sc);
    return rc ? -1 : 0;
}

/* RMS of material m against values v at samples s, and of v itself. */
static void rms_of(const material *m, const samples *s, const float *v, double *err,
                   double *ref)
{
    double se = 0.0, sr = 0.0;
    for (int i = 0; i < s->n; i++) {
        double n[3], wi[3], wo[3], f[3];
        dirs_of(s, i, n, wi, wo);
        material_eval(m, n, wi, wo, f);
        for (int c = 0; c < 3; c++) {
            double d = f[c] - v[3 * (size_t)i + c];
            se += d * d;
            sr += (double)v[3 * (size_t)i + c] * v[3 * (size_t)i + c];
        }
    }
    *err = sqrt(se / (3.0 * s->n));
    *ref = sqrt(sr / (3.0 * s->n));
}

int main(int argc, char **argv)
{
    static const char *const analytic[] = {"lambert:kd=0.8", "ct:rough=0.2,kd=0.5,f0=0.04",
                                           "ct:kd=0,f0=0.9/0.6/0.3,rough=0.3"};
    static const char *const measured_names[] = {"sgd:gray-plastic", "sgd:blue-acrylic",
                                                 "sgd:gold-metallic-paint2", "sgd:nickel",
                                                 "sgd:red-specular-plastic", "sgd:white-paint"};
    static const char *const kinds[] = {"dielectric", "conductor"};
    const char *mdir = "../shared/data/measured";
    int reps = 3, size = 128, ntruths = 0;
    truth truths[16];
    scene_params sp;
    samples train, test;
    glint_err e;
    char path[512];

    for (int a = 1; a < argc; a++) {
        if (!strcmp(argv[a], "--reps") && a + 1 < argc)
            reps = atoi(argv[++a]);
        else if (!strcmp(argv[a], "--size") && a + 1 < argc)
            size = atoi(argv[++a]);
        else if (!strcmp(argv[a], "--measured") && a + 1 < argc)
            mdir = argv[++a];
        else {
            fprintf(stderr, "usage: bench_pbr [--reps N] [--size S] [--measured DIR]\n");
            return 2;
        }
    }
    for (size_t i = 0; i < sizeof analytic / sizeof *analytic; i++) {
        memset(&truths[ntruths], 0, sizeof truths[0]);
        truths[ntruths].spec = analytic[i];
        if (brdf_parse(analytic[i], &truths[ntruths].b, &e)) {
            fprintf(stderr, "%s: %s\n", analytic[i], e.msg);
            return 1;
        }
        ntruths++;
    }
    snprintf(path, sizeof path, "%s/merl56_fits.json", mdir);
    if (access(path, R_OK) == 0) {
        measured_set_file(path, NULL);
        for (size_t i = 0; i < sizeof measured_names / sizeof *measured_names; i++) {
            memset(&truths[ntruths], 0, sizeof truths[0]);
            truths[ntruths].spec = measured_names[i];
            truths[ntruths].measured = 1;
            if (measured_truth_parse(measured_names[i], &truths[ntruths].mt, &e))
                fprintf(stderr, "%s: %s (skipped)\n", measured_names[i], e.msg);
            else
                ntruths++;
        }
    } else
        printf("(no %s: analytic truths only)\n", path);

    scene_params_default(&sp);
    sp.width = sp.height = size;
    if (samples_of(&sp, &train, &e))
        return fprintf(stderr, "training scene: %s\n", e.msg), 1;
    sp.view_set = SCENE_VIEWS_ICO20;
    sp.light_lo_deg = 5.0;
    sp.light_hi_deg = 85.0;
    sp.light_mid = 1;
    if (samples_of(&sp, &test, &e))
        return fprintf(stderr, "test scene: %s\n", e.msg), 1;
    printf("sphere %dx%d: 12 painted views, %d samples; 20 new views, %d samples; best of %d\n",
           size, size, train.n, test.n, reps);
    printf("%-34s %-10s %8s %8s %6s %9s %11s %8s %11s %8s\n", "truth", "fresnel", "wall ms",
           "cpu ms", "iters",
           "alpha", "rms painted", "rel", "rms new", "rel");

    for (int t = 0; t < ntruths; t++) {
        float *v = values_of(&truths[t], &train), *vt = values_of(&truths[t], &test);
        for (int k = 0; k < 2; k++) {
            pbr_params pp;
            method_build_in bin;
            method_fit_in in;
            cache_value lv = {0};
            const void *levels[1];
            const char *keys[1] = {"pbr-geom:bench"};
            double best = INFINITY, best_cpu = INFINITY, ep, rp, en, rn;
            material m = {0};
            method_pbr.params_default(&pp);
            pp.fresnel = k;
            memset(&bin, 0, sizeof bin);
            bin.params = &pp;
            bin.s = &train;
            if (method_pbr.levels[0].build(&bin, &lv, &e))
                return fprintf(stderr, "pbr-geom: %s\n", e.msg), 1;
            levels[0] = lv.data;
            memset(&in, 0, sizeof in);
            in.params = &pp;
            in.s = &train;
            in.rgb = v;
            in.levels = levels;
            in.keys = keys;
            for (int r = 0; r < reps; r++) {
                double t0 = glint_now(), c0 = cpu_now();
                material_free(&m);
                if (method_pbr.fit(&in, &m, &e))
                    return fprintf(stderr, "%s: %s\n", truths[t].spec, e.msg), 1;
                best = fmin(best, glint_now() - t0);
                best_cpu = fmin(best_cpu, cpu_now() - c0);
            }
            rms_of(&m, &train, v, &ep, &rp);
            rms_of(&m, &test, vt, &en, &rn);
            printf("%-34s %-10s %8.1f %8.1f %6d %9.4g %11.4g %7.2f%% %11.4g %7.2f%%\n",
                   truths[t].spec, kinds[k], 1e3 * best, 1e3 * best_cpu,
                   (int)json_integer_value(json_object_get(json_object_get(m.info, "fit"),
                                                           "iterations")),
                   pbr_material_of(&m)->lobe[0].alpha, ep, 100.0 * ep / rp, en,
                   100.0 * en / rn);
            fflush(stdout);
            material_free(&m);
            lv.free(lv.data);
        }
        free(v);
        free(vt);
    }
    samples_free(&train);
    samples_free(&test);
    return 0;
}
