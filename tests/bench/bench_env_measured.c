/* bench_env_measured.c: how fits of measured materials painted under an
 * environment hold up under new views and new light.
 *
 *   bench_env_measured [--data DIR] [--every K] [--first I] [--size WxH]
 *                      [--methods a,b] [--views 3,1] [--env A B] [--lights K]
 *                      [--set NAME=VALUE]... [--rim C]
 *
 * Methods: any environment method, and srbf+kd: srbf with its diffuse
 * colour given, the one pbr_env fits to the same painting (the lobes fit
 * what the parametric diffuse leaves); and abc, no fit: the other published
 * fit of the same measurements rendered as the prediction, how far apart
 * two fits of one material are on each set of views (the truth's own
 * uncertainty, measured.h).
 * --rim C: the errors also over the pixels whose n.wo is at least C (a
 * second table): what the rim, where a light behind the sphere makes its
 * brightest highlight at grazing angles, leaves out.
 * --env: environments A and B (specs, e.g. sky sunset); --lights: the
 * lights truths and renders sum; --set: a parameter of every method that
 * has it (e.g. start_samples=256), for the speed-accuracy trade.
 *
 * For every K-th material of DIR/measured/merl56_fits.json from the I-th
 * (default 4 from 0: 14 of the 56; the published sgd fits; another I
 * gives materials a setting was not chosen on): the sphere at WxH (default 64x48)
 * with the 20 views of the icosahedron's face centres; views 0, 7 and 14
 * painted (or view 0 alone) under environment A; each method (srbf,
 * pbr_env; their defaults, the environment named) fitted to them and its
 * material rendered where nothing was painted:
 *   new      the other views under A;
 *   rotated  those views under A turned 120 degrees about the up axis;
 *   other    those views under environment B.
 * A = DIR/envmaps/courtyard.exr, B = DIR/envmaps/sunset.exr (the built-in
 * sky and sunset when absent).  Truths and renders sum 256 median-cut
 * lights of the map (--lights): the lights `glint paint --env`, glintd's
 * base renders and the fits' precomputation use, so a painting is what an
 * artist paints over glint's own render of the scene.  With more (512,
 * 4096) the truths are lit more finely than a fit compresses the map, and
 * that compression's error is part of what is measured.  The sphere is
 * convex: no shadows.  The error of a set of views is the relative RMS over their
 * pixels, |render - truth| / |truth|, the material evaluated as previews
 * are (material_eval_preview: srbf's tabulated p(h), within 0.5%).
 * Printed per material the errors, then per method and view count the
 * median, the 90th percentile and the worst material, with the median warm
 * fit time (a second fit of the same painting, precomputation cached).
 *
 * Nothing here is asserted; the figures go to BENCHMARKS.md. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "cache.h"
#include "clock.h"
#include "env.h"
#include "material.h"
#include "measured.h"
#include "method_pbr_env.h"
#include "method.h"
#include "prep.h"
#include "samples.h"
#include "scene.h"
#include "bench_env.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

#define NVIEWS 20
#define MAXM 64
#define MAXMAT MEASURED_MAX

static int eval_lights = 256; /* --lights */
static double rim = -1.0;     /* --rim: the second table's n.wo floor; < 0: none */
static const char *sets[8]; /* --set NAME=VALUE: a parameter of every method that has it */
static int nsets;

/* What is rendered: a measured truth or a fitted material. */
typedef struct shader {
    const measured_truth *t;
    const material *m;
} shader;

/* f (n.wi) at unit vectors: a material's eval holds the cosine, a truth's
 * f does not. */
static void shade(const shader *sh, const double n[3], const double wi[3], const double wo[3],
                  double cs, double f[3])
{
    if (sh->t) {
        measured_eval(sh->t, n, wi, wo, f);
        for (int c = 0; c < 3; c++)
            f[c] *= cs;
    } else
        material_eval_preview(sh->m, n, wi, wo, f);
}

/* The samples of s under lights l (f cos summed; OUT rgb[3 n]). */
static void render(const samples *s, const env_lights *l, const shader *sh, float *rgb)
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
            shade(sh, n, d, wo, cs, v);
            for (int c = 0; c < 3; c++)
                acc[c] += l->power[3 * k + c] * v[c];
        }
        for (int c = 0; c < 3; c++)
            rgb[3 * i + c] = (float)acc[c];
    }
}

enum { E_PAINTED, E_NEW, E_ROT, E_OTHER, E_N };
static const char *const E_NAME[E_N] = {"painted", "new views", "rotated", "other env"};

typedef struct result {
    double e[E_N];
    double e_rim[E_N];  /* over the pixels with n.wo >= rim (--rim) */
    double fit_ms;
    int ok;
    char chose[96];  /* a method that chooses: the chosen candidate's label */
} result;

/* A material's truths over the views measured, rendered once for every
 * method (OUT of truth_get: the array for error k over s). */
typedef struct truths {
    const measured_truth *t;
    float *a[E_N];
} truths;

static void truths_free(truths *tr)
{
    for (int k = 0; k < E_N; k++)
        free(tr->a[k]);
    memset(tr->a, 0, sizeof tr->a);
}

typedef struct bench {
    cache *c;
    cache_entry *se;
    const char *envA;
    env_lights lA, lRot, lB;
} bench;

static const float *truth_get(truths *tr, int k, const samples *s, const env_lights *l)
{
    shader st = {tr->t, NULL};
    if (!tr->a[k] && (tr->a[k] = malloc((size_t)3 * s->n * sizeof(float))))
        render(s, l, &st, tr->a[k]);
    return tr->a[k];
}

/* The relative RMS of shader sm against truth k over s under l (OUT
 * r->e[k], and r->e_rim[k] over the pixels with n.wo >= rim). */
static void rel_rms(truths *tr, int k, const samples *s, const env_lights *l,
                    const shader *sm, result *r)
{
    const float *a = truth_get(tr, k, s, l);
    float *b = malloc((size_t)3 * s->n * sizeof *b);
    double num = 0.0, den = 0.0, rnum = 0.0, rden = 0.0;
    r->e[k] = r->e_rim[k] = NAN;
    if (!a || !b) {
        free(b);
        return;
    }
    render(s, l, sm, b);
    for (long i = 0; i < 3L * s->n; i++) {
        const float *nn = s->nrm + 3 * (i / 3), *wo = s->wo + 3 * (i / 3);
        double d2 = ((double)b[i] - a[i]) * ((double)b[i] - a[i]), t2 = (double)a[i] * a[i];
        num += d2;
        den += t2;
        if (nn[0] * wo[0] + nn[1] * wo[1] + nn[2] * wo[2] >= rim) {
            rnum += d2;
            rden += t2;
        }
    }
    if (getenv("BENCH_ENV_DEBUG")) { /* by view: error, and the view's share of |truth|^2 */
        double vn[64] = {0}, vd[64] = {0};
        for (long i = 0; i < 3L * s->n; i++) {
            int v = s->view[i / 3] & 63;
            vn[v] += ((double)b[i] - a[i]) * ((double)b[i] - a[i]);
            vd[v] += (double)a[i] * a[i];
        }
        printf("    error %d by view:", k);
        for (int v = 0; v < 64; v++)
            if (vd[v] > 0.0)
                printf(" %d:%.2f(%.0f%%)", v, sqrt(vn[v] / vd[v]), 100 * vd[v] / den);
        printf("\n");
    }
    free(b);
    r->e[k] = den > 0.0 ? sqrt(num / den) : NAN;
    r->e_rim[k] = rden > 0.0 ? sqrt(rnum / rden) : NAN;
}

/* The painting of s's views under A: the truth's radiance over each
 * sample's intensity, as a painting is given to a fit (malloc'ed, 3 n;
 * NULL when out of memory). */
static float *painting_of(bench *b, truths *tr, const samples *s)
{
    const float *t = truth_get(tr, E_PAINTED, s, &b->lA);
    float *rgb = t ? malloc((size_t)3 * s->n * sizeof *rgb) : NULL;
    for (long i = 0; rgb && i < 3L * s->n; i++)
        rgb[i] = (float)(t[i] / s->intensity[i / 3]);
    return rgb;
}

/* The diffuse colour pbr_env fits to the painting of the views of `use`
 * (OUT kd): what srbf is given with "srbf+kd" (its diffuse separated by
 * the parametric fit, the lobes fitted to the rest). */
static int pbr_env_kd(bench *b, truths *tr, const unsigned char *use, double kd[3],
                      glint_err *e)
{
    void *par = method_params_new(&method_pbr_env);
    prep *p = NULL;
    material mat;
    float *rgb = NULL;
    const samples *s;
    int rc = -1;
    memset(&mat, 0, sizeof mat);
    if (!par || method_param_set_text(&method_pbr_env, par, "env", b->envA, e))
        goto done;
    {
        prep_request rq = {&method_pbr_env, par, b->se, use, NULL};
        if (prep_acquire(b->c, &rq, NULL, NULL, &p, e))
            goto done;
    }
    s = prep_samples(p);
    if (!(rgb = painting_of(b, tr, s)) || prep_fit(p, NULL, rgb, &mat, e))
        goto done;
    memcpy(kd, pbr_material_of(&mat)->kd, 3 * sizeof(double));
    rc = 0;
done:
    free(rgb);
    material_free(&mat);
    prep_release(b->c, p);
    free(par);
    return rc;
}

/* One method fitted to one material painted in the views of `use` under A;
 * its errors (OUT r).  0, or -1 with the reason printed. */
static int run_one(bench *b, const method *m, int kd_given, truths *tr,
                   const unsigned char *use, const unsigned char *rest, result *r)
{
    void *par = method_params_new(m);
    prep *p = NULL, *pn = NULL;
    material mat, warm;
    glint_err e;
    float *rgb = NULL;
    const samples *s;
    const measured_truth *t = tr->t;
    int rc = -1;
    double t0;

    memset(&mat, 0, sizeof mat);
    memset(&warm, 0, sizeof warm);
    if (!par || method_param_set_text(m, par, "env", b->envA, &e))
        goto done;
    if (kd_given) {
        double kd[3];
        char txt[128];
        if (pbr_env_kd(b, tr, use, kd, &e))
            goto done;
        snprintf(txt, sizeof txt, "%.17g,%.17g,%.17g", kd[0], kd[1], kd[2]);
        if (method_param_set_text(m, par, "diffuse", txt, &e))
            goto done;
    }
    for (int k = 0; k < nsets; k++) {
        char name[64];
        const char *eq = strchr(sets[k], '=');
        snprintf(name, sizeof name, "%.*s", (int)(eq - sets[k]), sets[k]);
        if (method_param_find(m, name) && method_param_set_text(m, par, name, eq + 1, &e))
            goto done;
    }
    {
        prep_request rq = {m, par, b->se, use, NULL}, rn = {m, par, b->se, rest, NULL};
        if (prep_acquire(b->c, &rq, NULL, NULL, &p, &e) ||
            prep_acquire(b->c, &rn, NULL, NULL, &pn, &e))
            goto done;
    }
    s = prep_samples(p);
    if (!(rgb = painting_of(b, tr, s)) || prep_fit(p, NULL, rgb, &warm, &e))
        goto done;
    t0 = glint_now();
    if (prep_fit(p, NULL, rgb, &mat, &e))
        goto done;
    r->fit_ms = (glint_now() - t0) * 1e3;
    { /* a method that chooses: what it chose */
        const char *ch = json_string_value(
            json_object_get(json_object_get(mat.info, "choice"), "chosen_label"));
        snprintf(r->chose, sizeof r->chose, "%s", ch ? ch : "");
    }
    if (getenv("BENCH_ENV_DEBUG")) {
        char *txt = json_dumps(json_object_get(mat.info, "errors"), JSON_COMPACT);
        printf("    %s errors: %.600s\n", m->name, txt ? txt : "");
        free(txt);
    }
    {
        shader sm = {NULL, &mat};
        rel_rms(tr, E_PAINTED, s, &b->lA, &sm, r);
        s = prep_samples(pn);
        rel_rms(tr, E_NEW, s, &b->lA, &sm, r);
        rel_rms(tr, E_ROT, s, &b->lRot, &sm, r);
        rel_rms(tr, E_OTHER, s, &b->lB, &sm, r);
    }
    rc = 0;
done:
    if (rc)
        printf("  %s on %s: failed: %s\n", m->name, t->name, e.msg);
    free(rgb);
    material_free(&mat);
    material_free(&warm);
    prep_release(b->c, p);
    prep_release(b->c, pn);
    free(par);
    return rc;
}

/* No fit: `other` (the other published fit of tr's material) rendered as
 * the prediction on the views of `use` and `rest` (OUT r; the samples are
 * pbr_env's of those views).  0, or -1 with the reason printed. */
static int run_other_fit(bench *b, const measured_truth *other, truths *tr,
                         const unsigned char *use, const unsigned char *rest, result *r)
{
    void *par = method_params_new(&method_pbr_env);
    prep *p = NULL, *pn = NULL;
    shader sm = {other, NULL};
    glint_err e;
    int rc = -1;
    if (!par || method_param_set_text(&method_pbr_env, par, "env", b->envA, &e))
        goto done;
    {
        prep_request rq = {&method_pbr_env, par, b->se, use, NULL},
                     rn = {&method_pbr_env, par, b->se, rest, NULL};
        if (prep_acquire(b->c, &rq, NULL, NULL, &p, &e) ||
            prep_acquire(b->c, &rn, NULL, NULL, &pn, &e))
            goto done;
    }
    rel_rms(tr, E_PAINTED, prep_samples(p), &b->lA, &sm, r);
    rel_rms(tr, E_NEW, prep_samples(pn), &b->lA, &sm, r);
    rel_rms(tr, E_ROT, prep_samples(pn), &b->lRot, &sm, r);
    rel_rms(tr, E_OTHER, prep_samples(pn), &b->lB, &sm, r);
    r->fit_ms = 0.0;
    rc = 0;
done:
    if (rc)
        printf("  abc on %s: failed: %s\n", tr->t->name, e.msg);
    prep_release(b->c, p);
    prep_release(b->c, pn);
    free(par);
    return rc;
}

static int dcmp(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* The q-quantile of v[0..n), linear between order statistics (numpy's
 * default: the median of an even count is the mean of the middle two). */
static double pct(const double *v, int n, double q)
{
    double s[MAXMAT], x, f;
    int i;
    memcpy(s, v, (size_t)n * sizeof *s);
    qsort(s, (size_t)n, sizeof *s, dcmp);
    x = q * (n - 1);
    i = (int)floor(x);
    f = x - i;
    return i + 1 < n ? s[i] + f * (s[i + 1] - s[i]) : s[n - 1];
}

static void summary(const char *mname, int nv, const result *res, const measured_truth *mats,
                    int n, int of_rim)
{
    double v[MAXMAT], ms[MAXMAT];
    int idx[MAXMAT], k2 = 0;
    for (int i = 0; i < n; i++)
        if (res[i].ok)
            idx[k2++] = i;
    if (!k2)
        return;
    printf("| %s | %d |", mname, nv);
    for (int k = 0; k < E_N; k++) {
        int worst = idx[0];
        for (int j = 0; j < k2; j++) {
            const double *e = of_rim ? res[idx[j]].e_rim : res[idx[j]].e;
            v[j] = e[k];
            if (e[k] > (of_rim ? res[worst].e_rim : res[worst].e)[k])
                worst = idx[j];
        }
        printf(" %.1f%% / %.1f%%%s%s |", 100 * pct(v, k2, 0.5), 100 * pct(v, k2, 0.9),
               k == E_NEW ? ", worst " : "", k == E_NEW ? mats[worst].name : "");
    }
    for (int j = 0; j < k2; j++)
        ms[j] = res[idx[j]].fit_ms;
    printf(" %.0f |\n", pct(ms, k2, 0.5));
}

static void views_of(int nv, unsigned char *use, unsigned char *rest)
{
    static const int painted[3] = {0, 7, 14};
    memset(use, 0, SCENE_MAX_VIEWS);
    memset(rest, 0, SCENE_MAX_VIEWS);
    for (int k = 0; k < nv; k++)
        use[painted[k]] = 1;
    for (int v = 0; v < NVIEWS; v++)
        rest[v] = !use[v];
}

int main(int argc, char **argv)
{
    char path[1200], methods[256] = "srbf,pbr_env", viewsarg[32] = "3,1";
    const char *envA = "data:courtyard.exr", *envB = "data:sunset.exr";
    const method *ms[8];
    int kdg[8] = {0}, other[8] = {0};
    char mnames[8][32];
    int env_given = 0, every = 4, first = 0, w = 64, h = 48, nm = 0, nmat = 0, nvs[2], nnv = 0;
    measured_set set;
    measured_truth *mats, *amats;
    scene sc;
    bench b;
    glint_err e;
    struct stat st;

    bench_env_data_default();
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--data") && i + 1 < argc)
            snprintf(DATA, sizeof DATA, "%s", argv[++i]);
        else if (!strcmp(argv[i], "--every") && i + 1 < argc)
            every = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--first") && i + 1 < argc)
            first = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--size") && i + 1 < argc)
            sscanf(argv[++i], "%dx%d", &w, &h);
        else if (!strcmp(argv[i], "--methods") && i + 1 < argc)
            snprintf(methods, sizeof methods, "%s", argv[++i]);
        else if (!strcmp(argv[i], "--env") && i + 2 < argc) {
            envA = argv[++i];
            envB = argv[++i];
            env_given = 1;
        } else if (!strcmp(argv[i], "--lights") && i + 1 < argc)
            eval_lights = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--set") && i + 1 < argc && nsets < 8 &&
                 strchr(argv[i + 1], '=') && argv[i + 1][0] != '=')
            sets[nsets++] = argv[++i];
        else if (!strcmp(argv[i], "--views") && i + 1 < argc)
            snprintf(viewsarg, sizeof viewsarg, "%s", argv[++i]);
        else if (!strcmp(argv[i], "--rim") && i + 1 < argc) {
            char *end;
            rim = strtod(argv[++i], &end);
            if (*end || !(rim >= 0.0 && rim < 1.0)) {
                fprintf(stderr, "--rim takes n.wo in [0, 1)\n");
                return 2;
            }
        } else {
            fprintf(stderr, "usage: %s [--data DIR] [--every K] [--first I] [--size WxH] "
                            "[--methods a,b] [--views 3,1] [--env A B] [--lights K] "
                            "[--set NAME=VALUE]... [--rim C]\n",
                    argv[0]);
            return 2;
        }
    }
    if (every < 1 || first < 0 || first >= every || w < 8 || h < 8) {
        fprintf(stderr, "bad --every, --first (0 to every - 1) or --size\n");
        return 2;
    }
    for (char *tok = strtok(methods, ","); tok && nm < 8; tok = strtok(NULL, ",")) {
        /* srbf+kd: srbf given pbr_env's diffuse colour */
        kdg[nm] = !strcmp(tok, "srbf+kd");
        other[nm] = !strcmp(tok, "abc"); /* no fit: the other published fit */
        snprintf(mnames[nm], sizeof mnames[nm], "%s", tok);
        ms[nm] = other[nm] ? &method_pbr_env : method_find(kdg[nm] ? "srbf" : tok);
        if (!ms[nm++]) {
            fprintf(stderr, "unknown method %s\n", tok);
            return 2;
        }
    }
    for (char *tok = strtok(viewsarg, ","); tok && nnv < 2; tok = strtok(NULL, ","))
        nvs[nnv++] = atoi(tok) == 1 ? 1 : 3;
    snprintf(path, sizeof path, "%s/measured/%s", DATA, MEASURED_FITS_FILE);
    if (stat(path, &st)) {
        printf("bench_env_measured: %s absent: nothing measured\n", path);
        return 0;
    }
    if (measured_load(path, &set, &e)) {
        fprintf(stderr, "%s\n", e.msg);
        return 1;
    }
    env_set_resolver(data_resolver);
    snprintf(path, sizeof path, "%s/envmaps/courtyard.exr", DATA);
    if (!env_given && stat(path, &st)) {
        envA = "sky";
        envB = "sunset";
    }
    mats = calloc((size_t)set.n, sizeof *mats);
    amats = calloc((size_t)set.n, sizeof *amats);
    for (int i = first; i < set.n; i += every) {
        measured_truth_of(&set.m[i], MEASURED_ABC, &amats[nmat]);
        measured_truth_of(&set.m[i], MEASURED_SGD, &mats[nmat++]);
    }
    {
        scene_params sp;
        scene_params_default(&sp);
        sp.width = w;
        sp.height = h;
        sp.view_set = SCENE_VIEWS_ICO20;
        if (scene_create(&sp, &sc, &e)) {
            fprintf(stderr, "%s\n", e.msg);
            return 1;
        }
    }
    memset(&b, 0, sizeof b);
    b.envA = envA;
    if (lights_of(envA, eval_lights, 0.0, &b.lA, &e) ||
        lights_of(envA, eval_lights, 120.0, &b.lRot, &e) ||
        lights_of(envB, eval_lights, 0.0, &b.lB, &e) || cache_open(NULL, (size_t)8 << 30, &b.c, &e)) {
        fprintf(stderr, "%s\n", e.msg);
        return 1;
    }
    {
        prep_scene_source src = {borrowed, NULL, &sc};
        if (prep_scene_acquire(b.c, "s", &src, &b.se, &e)) {
            fprintf(stderr, "%s\n", e.msg);
            return 1;
        }
    }
    printf("# %d sgd materials (every %d of %d from %d), sphere %dx%d, environment %s (rotated "
           "120 degrees; other: %s), truths and renders with %d lights\n",
           nmat, every, set.n, first, w, h, envA, envB, eval_lights);
    result *res = calloc((size_t)2 * nm * nmat, sizeof *res);
    for (int vi = 0; vi < nnv; vi++) {
        unsigned char use[SCENE_MAX_VIEWS], rest[SCENE_MAX_VIEWS];
        views_of(nvs[vi], use, rest);
        for (int i = 0; i < nmat; i++) {
            truths tr = {&mats[i], {NULL}};
            for (int mi = 0; mi < nm; mi++) {
                result *r = &res[((size_t)vi * nm + mi) * nmat + i];
                if (other[mi] ? run_other_fit(&b, &amats[i], &tr, use, rest, r)
                              : run_one(&b, ms[mi], kdg[mi], &tr, use, rest, r))
                    continue;
                r->ok = 1;
                printf("  %-28s %-8s %d view%s: painted %.4f new %.4f rotated %.4f other %.4f "
                       "(%.0f ms)%s%s\n", mats[i].name, mnames[mi], nvs[vi],
                       nvs[vi] > 1 ? "s" : "", r->e[E_PAINTED], r->e[E_NEW], r->e[E_ROT],
                       r->e[E_OTHER], r->fit_ms, r->chose[0] ? " chose: " : "", r->chose);
                if (rim >= 0.0)
                    printf("  %-28s %-8s %d view%s, n.wo >= %g: painted %.4f new %.4f rotated "
                           "%.4f other %.4f\n", mats[i].name, mnames[mi], nvs[vi],
                           nvs[vi] > 1 ? "s" : "", rim, r->e_rim[E_PAINTED], r->e_rim[E_NEW],
                           r->e_rim[E_ROT], r->e_rim[E_OTHER]);
                fflush(stdout);
            }
            truths_free(&tr);
        }
    }
    for (int of_rim = 0; of_rim <= (rim >= 0.0); of_rim++) {
        if (of_rim)
            printf("\nOver the pixels with n.wo >= %g:\n", rim);
        printf("\n| method | views |");
        for (int k = 0; k < E_N; k++)
            printf(" %s median / p90 |", E_NAME[k]);
        printf(" warm fit ms (median) |\n|---|---|---|---|---|---|---|\n");
        for (int vi = 0; vi < nnv; vi++)
            for (int mi = 0; mi < nm; mi++)
                summary(mnames[mi], nvs[vi], res + ((size_t)vi * nm + mi) * nmat, mats, nmat,
                        of_rim);
    }
    free(res);
    cache_release(b.c, b.se);
    cache_close(b.c);
    env_lights_free(&b.lA);
    env_lights_free(&b.lRot);
    env_lights_free(&b.lB);
    scene_free(&sc);
    measured_free(&set);
    free(mats);
    free(amats);
    return 0;
}
