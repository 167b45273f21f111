/* test_pbr_detail.c: the pbr_detail method (core/methods/pbr_detail): the
 * pbr fit times a three-factor detail of the ratio painted / base.
 *
 *   - a truth of the pbr model itself: the product equals the base (the
 *     detail's ratio within 1e-3 of 1 at every sample) and its painted
 *     error is no worse than the base's by more than 1e-6;
 *   - truths the GGX family cannot represent (a Phong lobe; measured sgd
 *     fits from ../shared/data/measured when present): the product's
 *     painted error is below 0.8 of the base's alone (measured: 20% to 66%);
 *   - the levels are pbr's and hf3's own cache entries: after a
 *     pbr_detail preparation, pbr's and hf3's are in memory;
 *   - the material saved and read back evaluates as the fitted one, and
 *     damaged manifests are refused with a message;
 *   - the GPU binding holds the detail's texture and both parts' uniforms;
 *   - extremes: an all-black painting, a single painted sample, NaN and inf
 *     (refused, named), one view only.
 *
 * The scene is the default sphere (12 point-lit views) at 64 x 64; values
 * are f ci per unit light (scene.h), computed at the samples. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "brdf.h"
#include "cache.h"
#include "check.h"
#include "material.h"
#include "measured.h"
#include "method_pbr_detail.h"
#include "prep.h"
#include "samples.h"
#include "scene.h"

static scene SC;
static cache *C;
static cache_entry *SE;

static int borrowed(void *cls, const char *id, const scene **out, glint_err *err)
{
    (void)id;
    (void)err;
    *out = cls;
    return 0;
}

static int setup(void)
{
    scene_params p;
    glint_err e;
    prep_scene_source src = {borrowed, NULL, &SC};
    if (C)
        return 0;
    scene_params_default(&p);
    p.width = p.height = 64;
    if (scene_create(&p, &SC, &e) || cache_open(NULL, (size_t)2 << 30, &C, &e) ||
        prep_scene_acquire(C, "sphere", &src, &SE, &e)) {
        fprintf(stderr, "setup: %s\n", e.msg);
        return -1;
    }
    return 0;
}

/* The default parameters at res 64 (a quarter of the default's work). */
static void params_small(pbr_detail_params *p)
{
    method_pbr_detail.params_default(p);
    p->hf.res = 64;
}

/* A preparation of method m (params) for the views flagged in use (NULL:
 * every view). */
static prep *prep_of(const method *m, const void *params, const unsigned char *use)
{
    unsigned char all[SCENE_MAX_VIEWS];
    prep_request rq;
    prep *pp = NULL;
    glint_err e;
    memset(all, 0, sizeof all);
    for (int v = 0; v < SC.nviews; v++)
        all[v] = 1;
    rq.m = m;
    rq.params = params;
    rq.scene = SE;
    rq.use = use ? use : all;
    rq.cancel = NULL;
    if (prep_acquire(C, &rq, NULL, NULL, &pp, &e)) {
        fprintf(stderr, "prep: %s\n", e.msg);
        return NULL;
    }
    return pp;
}

static void dirs_of(const samples *s, int i, double n[3], double wi[3], double wo[3])
{
    for (int a = 0; a < 3; a++) {
        n[a] = s->nrm[3 * (size_t)i + a];
        wi[a] = s->wi[3 * (size_t)i + a];
        wo[a] = s->wo[3 * (size_t)i + a];
    }
}

typedef void (*truth_fn)(const void *cls, const double n[3], const double wi[3],
                         const double wo[3], double f[3]);

static void brdf_truth(const void *cls, const double n[3], const double wi[3],
                       const double wo[3], double f[3])
{
    brdf_eval(cls, n, wi, wo, f);
}

static void pbr_truth(const void *cls, const double n[3], const double wi[3],
                      const double wo[3], double f[3])
{
    pbr_detail_base_brdf(cls, n, wi, wo, f);
}

/* f ci of a truth at every sample (malloc'ed, 3 n). */
static float *values_of(truth_fn f, const void *cls, const samples *s)
{
    float *v = malloc(3 * sizeof(float) * (size_t)(s->n ? s->n : 1));
    for (int i = 0; v && i < s->n; i++) {
        double n[3], wi[3], wo[3], x[3];
        dirs_of(s, i, n, wi, wo);
        f(cls, n, wi, wo, x);
        for (int c = 0; c < 3; c++)
            v[3 * (size_t)i + c] = (float)(x[c] * s->cos_i[i]);
    }
    return v;
}

/* The product's and the base's painted errors per unit light (the blend
 * report: the top-level errors are scaled by the views' light intensity). */
static double blend_num(const material *m, const char *key)
{
    return json_number_value(json_object_get(json_object_get(m->info, "blend"), key));
}

static double rms_painted(const material *m)
{
    return blend_num(m, "rms_painted");
}

static double base_rms(const material *m)
{
    return blend_num(m, "rms_painted_base");
}

static double values_rms(const float *v, int n)
{
    double ss = 0.0;
    for (int i = 0; i < 3 * n; i++)
        ss += (double)v[i] * v[i];
    return n ? sqrt(ss / (3.0 * n)) : 0.0;
}

/* Fit truth values on every view; 0 or the fit's code (message in *e). */
static int fit_truth(truth_fn f, const void *cls, material *m, glint_err *e)
{
    pbr_detail_params p;
    prep *pp;
    float *v;
    int rc;
    params_small(&p);
    if (!(pp = prep_of(&method_pbr_detail, &p, NULL)))
        return glint_err_set(e, GLINT_EINTERNAL, "no preparation");
    v = values_of(f, cls, prep_samples(pp));
    rc = v ? prep_fit(pp, NULL, v, m, e) : GLINT_ENOMEM;
    free(v);
    prep_release(C, pp);
    return rc;
}

/* A pbr material of known parameters: kd, one dielectric lobe. */
static void known_base(pbr_material *pm)
{
    static const double p[8] = {0.45, 0.3, 0.15, 0.18, 0.9, 0.8, 0.7, 1.5};
    memset(pm, 0, sizeof *pm);
    pm->sp.nlobes = 1;
    pm->sp.fresnel = PBR_DIELECTRIC;
    memcpy(pm->p, p, sizeof p);
    pbr_material_sync(pm);
}

TEST(ggx_truth_leaves_the_detail_at_one)
{
    pbr_material truth;
    material m = {0};
    glint_err e;
    const pbr_detail_material *x;
    double worst = 0.0, rb, rp;
    prep *pp;
    pbr_detail_params p;
    const samples *s;

    ASSERT(setup() == 0);
    known_base(&truth);
    ASSERT_OK(fit_truth(pbr_truth, &truth, &m, &e));
    ASSERT((x = pbr_detail_material_of(&m)) != NULL);
    rb = base_rms(&m);
    rp = rms_painted(&m);
    printf("  GGX truth: base rms %.3g, product rms %.3g\n", rb, rp);
    ASSERT_LE(rp, rb + 1e-6);
    /* the detail over ci is the ratio: 1 wherever the base is exact */
    params_small(&p);
    ASSERT((pp = prep_of(&method_pbr_detail, &p, NULL)) != NULL);
    s = prep_samples(pp);
    for (int i = 0; i < s->n; i++) {
        double n[3], wi[3], wo[3], d[3];
        dirs_of(s, i, n, wi, wo);
        hf_factors_eval(&x->detail, n, wi, wo, d);
        for (int c = 0; c < 3; c++)
            worst = fmax(worst, fabs(d[c] / s->cos_i[i] - 1.0));
    }
    printf("  detail's largest |ratio - 1|: %.3g\n", worst);
    ASSERT_LT(worst, 1e-3);
    prep_release(C, pp);
    material_free(&m);
}

TEST(levels_are_pbr_and_hf3_entries)
{
    pbr_detail_params p;
    prep *pp, *q = NULL;
    glint_err e;
    unsigned char all[SCENE_MAX_VIEWS] = {0};
    prep_request rq = {NULL, NULL, NULL, all, NULL};

    ASSERT(setup() == 0);
    params_small(&p);
    ASSERT((pp = prep_of(&method_pbr_detail, &p, NULL)) != NULL);
    for (int v = 0; v < SC.nviews; v++)
        all[v] = 1;
    rq.scene = SE;
    /* nothing is built for pbr or hf3 at the same res: every level is there */
    rq.m = &method_pbr;
    rq.params = &p.pbr;
    ASSERT_OK(prep_try(C, &rq, &q, &e));
    prep_release(C, q);
    rq.m = &method_hf3;
    rq.params = &p.hf;
    ASSERT_OK(prep_try(C, &rq, &q, &e));
    prep_release(C, q);
    /* a res no one asked for is not */
    p.hf.res = 40;
    ASSERT(prep_try(C, &rq, &q, &e) == GLINT_ENOTFOUND);
    prep_release(C, pp);
}

/* The product's painted error against the base's, for a truth the GGX
 * family cannot hold. */
static void check_beats_base(truth_fn f, const void *cls, const char *what)
{
    material m = {0};
    glint_err e;
    double rb, rp;
    ASSERT_MSG(fit_truth(f, cls, &m, &e) == 0, "%s: %s", what, e.msg);
    rb = base_rms(&m);
    rp = rms_painted(&m);
    printf("  %s: base rms %.4g, whole detail %.4g, product rms %.4g (%.0f%%), weight %s\n",
           what, rb, blend_num(&m, "rms_painted_whole"), rp, 100.0 * rp / rb,
           json_dumps(json_object_get(json_object_get(m.info, "blend"), "weight"), JSON_COMPACT));
    ASSERT_FINITE(rp);
    ASSERT_LT(rp, 0.8 * rb);
    material_free(&m);
}

TEST(non_ggx_truth_gains_from_the_detail)
{
    brdf b;
    glint_err e;
    ASSERT(setup() == 0);
    ASSERT_OK(brdf_parse("phong:kd=0.4/0.3/0.2,ks=0.4,e=32", &b, &e));
    check_beats_base(brdf_truth, &b, "phong e 32");
}

static void measured_fn(const void *cls, const double n[3], const double wi[3],
                           const double wo[3], double f[3])
{
    measured_eval(cls, n, wi, wo, f);
}

TEST(measured_truths_gain_from_the_detail)
{
    static const char *const names[] = {"gold-metallic-paint2", "red-specular-plastic",
                                        "pickled-oak-260"};
    measured_set set = {0};
    const char *data = check_data_dir();
    char path[4200];
    glint_err e;
    ASSERT(setup() == 0);
    if (!data ||
        (size_t)snprintf(path, sizeof path, "%s/measured/%s", data, MEASURED_FITS_FILE) >=
            sizeof path ||
        access(path, R_OK) != 0) {
        printf("  skipped: no measured fits under the shared data\n");
        return;
    }
    ASSERT_OK(measured_load(path, &set, &e));
    for (size_t k = 0; k < sizeof names / sizeof names[0]; k++) {
        const measured_material *mm = measured_find(&set, names[k]);
        measured_truth t;
        char what[96];
        if (!mm) {
            printf("  %s: not in the fits file\n", names[k]);
            continue;
        }
        measured_truth_of(mm, MEASURED_SGD, &t);
        snprintf(what, sizeof what, "sgd:%s", names[k]);
        check_beats_base(measured_fn, &t, what);
    }
    measured_free(&set);
}

/* The largest |a - b| / (|b| + 1e-12) of two materials over a grid of
 * direction pairs (normal +Z). */
static double materials_diff(const material *a, const material *b)
{
    const double n[3] = {0, 0, 1};
    double worst = 0.0;
    for (int ti = 0; ti < 9; ti++)
        for (int to = 0; to < 9; to++)
            for (int ph = 0; ph < 8; ph++) {
                double t1 = 0.17 * ti + 0.01, t2 = 0.17 * to + 0.02, p = 0.8 * ph;
                double wi[3] = {sin(t1), 0, cos(t1)};
                double wo[3] = {sin(t2) * cos(p), sin(t2) * sin(p), cos(t2)};
                double x[3], y[3];
                material_eval(a, n, wi, wo, x);
                material_eval(b, n, wi, wo, y);
                for (int c = 0; c < 3; c++)
                    worst = fmax(worst, fabs(x[c] - y[c]) / (fabs(y[c]) + 1e-12));
            }
    return worst;
}

/* Rewrite dir/material.json with member `key` of part `part` replaced by
 * `value` (JSON text); NULL value: the part removed. */
static int damage(const char *dir, const char *part, const char *key, const char *value)
{
    char path[256];
    json_t *root, *o;
    int rc;
    snprintf(path, sizeof path, "%s/material.json", dir);
    if (!(root = json_load_file(path, 0, NULL)))
        return -1;
    if (!value)
        json_object_del(root, part);
    else if ((o = json_object_get(root, part)))
        json_object_set_new(o, key, json_loads(value, JSON_DECODE_ANY, NULL));
    rc = json_dump_file(root, path, 0);
    json_decref(root);
    return rc;
}

TEST(material_files_round_trip_and_damage)
{
    brdf b;
    material m = {0}, r = {0};
    glint_err e;
    char dir[] = "/tmp/glint-pbr-detail-XXXXXX", path[256];
    static const char *const files[] = {"material.json", "factors.exr", "factors.png"};
    double d;
    json_t *sum;

    ASSERT(setup() == 0);
    ASSERT_OK(brdf_parse("phong:kd=0.4/0.3/0.2,ks=0.4,e=32", &b, &e));
    ASSERT_OK(fit_truth(brdf_truth, &b, &m, &e));
    ASSERT(mkdtemp(dir) != NULL);
    ASSERT_OK(material_save(&m, dir, &e));
    ASSERT_OK(material_load(dir, &r, &e));
    ASSERT(pbr_detail_material_of(&r) != NULL);
    d = materials_diff(&r, &m);
    printf("  read back: largest relative difference %.3g\n", d);
    ASSERT_LT(d, 1e-12);
    /* the summary: the base's numbers and a word on the detail */
    ASSERT((sum = material_summary(&r)) != NULL);
    ASSERT(json_is_string(json_object_get(sum, "fresnel")));
    ASSERT(json_is_number(json_object_get(sum, "alpha")));
    ASSERT(json_is_string(json_object_get(sum, "detail")));
    json_decref(sum);
    material_free(&r);
    /* damaged parts are refused by their own method's checks, named */
    ASSERT(damage(dir, "base", "fresnel", "\"glass\"") == 0);
    ASSERT(material_load(dir, &r, &e) == GLINT_EFORMAT);
    ASSERT_MSG(strstr(e.msg, "base") && strstr(e.msg, "fresnel"), "%s", e.msg);
    ASSERT_OK(material_save(&m, dir, &e));
    ASSERT(damage(dir, "detail", "res", "1") == 0);
    ASSERT(material_load(dir, &r, &e) == GLINT_EFORMAT);
    ASSERT_MSG(strstr(e.msg, "detail") && strstr(e.msg, "res"), "%s", e.msg);
    ASSERT(damage(dir, "detail", NULL, NULL) == 0);
    ASSERT(material_load(dir, &r, &e) == GLINT_EFORMAT);
    ASSERT_MSG(strstr(e.msg, "detail must be an object"), "%s", e.msg);
    for (size_t k = 0; k < sizeof files / sizeof files[0]; k++) {
        snprintf(path, sizeof path, "%s/%s", dir, files[k]);
        unlink(path);
    }
    rmdir(dir);
    material_free(&m);
}

TEST(gpu_binding_holds_both_parts)
{
    pbr_material truth;
    material m = {0};
    material_gpu g;
    glint_err e;
    ASSERT(setup() == 0);
    known_base(&truth);
    ASSERT_OK(fit_truth(pbr_truth, &truth, &m, &e));
    ASSERT_OK(material_gpu_get(&m, &g, &e));
    ASSERT(g.frag_src && strstr(g.frag_src, "glint_material") && g.tex);
    ASSERT_EQ(g.tex_w, pbr_detail_material_of(&m)->detail.res);
    ASSERT_EQ(g.tex_h, 3);
    ASSERT_EQ(g.nuniforms, 12);
    for (int i = 0; i < g.nuniforms; i++)
        ASSERT_MSG(strstr(g.frag_src, g.uniform[i].name), "%s not in the shader",
                   g.uniform[i].name);
    ASSERT(json_is_object(json_object_get(g.manifest, "base")));
    ASSERT(json_is_object(json_object_get(g.manifest, "detail")));
    material_gpu_free(&g);
    material_free(&m);
}

/* Evaluation finite (and >= 0) over a grid of direction pairs. */
static int eval_finite(const material *m)
{
    const double n[3] = {0, 0, 1};
    for (int ti = 0; ti < 10; ti++)
        for (int to = 0; to < 10; to++) {
            double t1 = 0.157 * ti, t2 = 0.157 * to + 0.05;
            double wi[3] = {sin(t1), 0, cos(t1)}, wo[3] = {-sin(t2), 0.1, cos(t2)}, x[3];
            material_eval(m, n, wi, wo, x);
            for (int c = 0; c < 3; c++)
                if (!isfinite(x[c]) || x[c] < 0.0)
                    return 0;
        }
    return 1;
}

/* Fit values v (3 n for preparation pp's samples). */
static int fit_values(prep *pp, const float *v, material *m, glint_err *e)
{
    return prep_fit(pp, NULL, v, m, e);
}

TEST(extremes)
{
    pbr_detail_params p;
    prep *pp;
    const samples *s;
    float *v;
    material m = {0};
    glint_err e;
    const json_t *fl;

    ASSERT(setup() == 0);
    params_small(&p);
    ASSERT((pp = prep_of(&method_pbr_detail, &p, NULL)) != NULL);
    s = prep_samples(pp);
    ASSERT((v = calloc(3 * (size_t)s->n, sizeof *v)) != NULL);
    /* all black: a black material, every sample at the floor */
    ASSERT_OK(fit_values(pp, v, &m, &e));
    ASSERT(eval_finite(&m));
    ASSERT_LE(rms_painted(&m), 1e-12);
    fl = json_object_get(json_object_get(m.info, "floor"), "samples_at_floor");
    ASSERT_EQ(json_integer_value(json_array_get(fl, 0)), s->n);
    material_free(&m);
    /* a single painted sample: a finite material or a clear error */
    v[3 * (s->n / 2)] = v[3 * (s->n / 2) + 1] = v[3 * (s->n / 2) + 2] = 0.5f;
    if (fit_values(pp, v, &m, &e) == 0) {
        ASSERT(eval_finite(&m));
        ASSERT_FINITE(rms_painted(&m));
        ASSERT_LE(rms_painted(&m), values_rms(v, s->n));
    } else {
        ASSERT(e.code != GLINT_EINTERNAL && e.msg[0]);
    }
    material_free(&m);
    /* NaN and inf: refused, the sample named */
    v[3 * 7 + 1] = NAN;
    ASSERT(fit_values(pp, v, &m, &e) == GLINT_ENONFINITE);
    ASSERT_MSG(strstr(e.msg, "pbr_detail") && strstr(e.msg, "sample 7"), "%s", e.msg);
    v[3 * 7 + 1] = INFINITY;
    ASSERT(fit_values(pp, v, &m, &e) == GLINT_ENONFINITE);
    ASSERT(m.method == NULL);
    free(v);
    prep_release(C, pp);
}

TEST(one_view_only)
{
    pbr_detail_params p;
    unsigned char one[SCENE_MAX_VIEWS] = {1};
    prep *pp;
    brdf b;
    float *v;
    material m = {0};
    glint_err e;
    const json_t *byv;

    ASSERT(setup() == 0);
    params_small(&p);
    ASSERT_OK(brdf_parse("phong:kd=0.4/0.3/0.2,ks=0.4,e=32", &b, &e));
    ASSERT((pp = prep_of(&method_pbr_detail, &p, one)) != NULL);
    ASSERT((v = values_of(brdf_truth, &b, prep_samples(pp))) != NULL);
    ASSERT_OK(fit_values(pp, v, &m, &e));
    ASSERT(eval_finite(&m));
    byv = json_object_get(json_object_get(m.info, "errors"), "rms_by_view");
    ASSERT_EQ(json_array_size(byv), 1);
    printf("  one view: base rms %.4g, product rms %.4g\n", base_rms(&m), rms_painted(&m));
    ASSERT_LE(rms_painted(&m), base_rms(&m));
    material_free(&m);
    free(v);
    prep_release(C, pp);
}

TEST_LIST {
    TEST_ENTRY(ggx_truth_leaves_the_detail_at_one),
    TEST_ENTRY(levels_are_pbr_and_hf3_entries),
    TEST_ENTRY(non_ggx_truth_gains_from_the_detail),
    TEST_ENTRY(measured_truths_gain_from_the_detail),
    TEST_ENTRY(material_files_round_trip_and_damage),
    TEST_ENTRY(gpu_binding_holds_both_parts),
    TEST_ENTRY(extremes),
    TEST_ENTRY(one_view_only),
};

TEST_MAIN()
