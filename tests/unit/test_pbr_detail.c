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

#include "check.h"
#include "method_pbr_detail.h"
#include "point_fixture.h"

/* The default parameters at res 64 (a quarter of the default's work). */
static void params_small(pbr_detail_params *p)
{
    method_pbr_detail.params_default(p);
    p->hf.res = 64;
}

static void pbr_truth(const void *cls, const double n[3], const double wi[3],
                      const double wo[3], double f[3])
{
    pbr_detail_base_brdf(cls, n, wi, wo, f);
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

TEST(measured_truths_gain_from_the_detail)
{
    ASSERT(setup() == 0);
    each_measured(check_beats_base);
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
