/* test_pbr_env.c: the pbr_env method (core/methods/pbr_env): pbr's model
 * fitted to views painted under an environment.
 *
 * Paintings are rendered here, independently of the method's terms: at
 * every sample, the sum over the environment's median-cut lights above
 * its horizon of power x f x cos, f a pbr material's own evaluation
 * (pbr_brdf through material_eval), divided by the sample's intensity as a
 * painting is.  The built-in sky lights them (no data needed); the sphere
 * is convex, so no shadow is cast.
 *
 *   - a truth of the model: its parameters come back (kd within 1%, the
 *     roughness within 2%), the painted error is below 1e-3 of the
 *     painting, and under the environment turned 120 degrees on a view
 *     never painted the material renders as the truth does (within 1%);
 *   - the prediction (prep_predict: the method's, over its terms) equals the independent
 *     render of the fitted material at every fitted pixel (1e-5 relative);
 *   - the lights and rows levels are srbf's own cache keys;
 *   - a material saved and read back is a pbr material evaluating alike;
 *   - extremes: all-black (black, roughness undetermined, said so), a
 *     single painted pixel, a painting brighter than any physical
 *     material (diffuse clamped at 1, said so), a Lambertian (roughness
 *     undetermined), a mirror (roughness at its floor), NaN and inf
 *     (refused, named), one view only. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "env_fixture.h"

/* Defaults under the sky, 64 lights (a quarter of the default's work). */
static void params_of(pbr_env_params *p)
{
    method_pbr_env.params_default(p);
    snprintf(p->env.env, sizeof p->env.env, "sky");
    p->env.lights = 64;
}

static prep *prep_of(const pbr_env_params *params, const unsigned char *use)
{
    return prep_method(&method_pbr_env, params, use);
}

static double num_at(const material *m, const char *a, const char *b)
{
    return json_number_value(json_object_get(json_object_get(m->info, a), b));
}

static int in_list(const material *m, const char *list, const char *name)
{
    const json_t *a = json_object_get(m->info, list), *x;
    size_t i;
    json_array_foreach(a, i, x) {
        const char *s = json_is_string(x) ? json_string_value(x)
                                          : json_string_value(json_object_get(x, "name"));
        if (s && !strcmp(s, name))
            return 1;
    }
    return 0;
}

static int notes_say(const material *m, const char *words)
{
    const json_t *a = json_object_get(m->info, "notes"), *x;
    size_t i;
    json_array_foreach(a, i, x)
        if (strstr(json_string_value(x), words))
            return 1;
    return 0;
}

TEST(model_truth_comes_back_and_holds_under_a_turned_environment)
{
    pbr_env_params p;
    env_lights l, lr;
    material truth, m;
    glint_err e;
    prep *pp, *pn;
    unsigned char other[SCENE_MAX_VIEWS] = {0};
    float *v, *t, *r;
    const pbr_material *pm;

    ASSERT(setup() == 0);
    params_of(&p);
    ASSERT_OK(lights_of(0.0, p.env.lights, &l));
    ASSERT_OK(lights_of(120.0, p.env.lights, &lr));
    known(&truth, 0.3, 0.2, 0.1, 0.25, 0.8, 1.5);
    ASSERT((pp = prep_of(&p, NULL)) != NULL);
    ASSERT((v = paint(&truth, prep_samples(pp), &l)) != NULL);
    ASSERT_OK(prep_fit(pp, NULL, v, &m, &e));
    ASSERT((pm = pbr_material_of(&m)) != NULL);
    printf("  kd %.4f %.4f %.4f alpha %.4f ks %.4f ior %.4f, painted rms %.3g\n", pm->kd[0],
           pm->kd[1], pm->kd[2], pm->lobe[0].alpha, pm->lobe[0].ks[0], pm->p[7],
           num_at(&m, "errors", "rms_painted"));
    ASSERT_NEAR(pm->kd[0], 0.3, 0.003);
    ASSERT_NEAR(pm->kd[1], 0.2, 0.002);
    ASSERT_NEAR(pm->kd[2], 0.1, 0.001);
    ASSERT_NEAR(pm->lobe[0].alpha, 0.25, 0.005);
    {
        float *back = paint(&m, prep_samples(pp), &l);
        ASSERT_LT(rel_diff(back, v, 3L * prep_samples(pp)->n), 1e-3);
        free(back);
    }
    /* a view never painted, the environment turned */
    other[1] = 1;
    ASSERT((pn = prep_of(&p, other)) != NULL);
    t = paint(&truth, prep_samples(pn), &lr);
    r = paint(&m, prep_samples(pn), &lr);
    printf("  view 1, environment turned 120 degrees: relative error %.3g\n",
           rel_diff(r, t, 3L * prep_samples(pn)->n));
    ASSERT_LT(rel_diff(r, t, 3L * prep_samples(pn)->n), 0.01);
    free(t);
    free(r);
    free(v);
    material_free(&m);
    material_free(&truth);
    env_lights_free(&l);
    env_lights_free(&lr);
    prep_release(C, pp);
    prep_release(C, pn);
}

TEST(prediction_is_the_independent_render)
{
    pbr_env_params p;
    env_lights l;
    material truth, m;
    glint_err e;
    prep *pp;
    float *v;
    long fitted;
    double d;

    ASSERT(setup() == 0);
    params_of(&p);
    ASSERT_OK(lights_of(0.0, p.env.lights, &l));
    known(&truth, 0.5, 0.4, 0.3, 0.1, 2.0, 1.8);
    ASSERT((pp = prep_of(&p, NULL)) != NULL);
    v = paint(&truth, prep_samples(pp), &l);
    ASSERT_OK(prep_fit(pp, NULL, v, &m, &e));
    d = predicted_vs_render(pp, &m, &l, &fitted);
    printf("  %ld values predicted, relative difference %.3g\n", fitted, d);
    ASSERT(fitted > 0);
    ASSERT(d >= 0.0);
    ASSERT_LT(d, 1e-5);
    free(v);
    material_free(&m);
    material_free(&truth);
    env_lights_free(&l);
    prep_release(C, pp);
}

TEST(lights_and_rows_are_srbf_levels)
{
    pbr_env_params p;
    char a[256], b[256], pa[256], pb[256];
    ASSERT(setup() == 0);
    params_of(&p);
    /* keyed as srbf keys them, from the same members */
    method_pbr_env.levels[0].key(&p, NULL, "x", a, sizeof a);
    method_srbf.levels[1].key(&p.env, NULL, "x", b, sizeof b);
    ASSERT(strcmp(a, b) == 0);
    {
        prep *pp = prep_of(&p, NULL);
        const samples *s;
        ASSERT(pp != NULL);
        s = prep_samples(pp);
        method_pbr_env.levels[1].key(&p, s, a, pa, sizeof pa);
        method_srbf.levels[2].key(&p.env, s, b, pb, sizeof pb);
        ASSERT(strcmp(pa, pb) == 0);
        prep_release(C, pp);
    }
}

TEST(material_round_trip)
{
    pbr_env_params p;
    env_lights l;
    material truth, m, back;
    glint_err e;
    prep *pp;
    float *v;
    double d;

    ASSERT(setup() == 0);
    params_of(&p);
    ASSERT_OK(lights_of(0.0, p.env.lights, &l));
    known(&truth, 0.2, 0.3, 0.4, 0.3, 1.0, 1.5);
    ASSERT((pp = prep_of(&p, NULL)) != NULL);
    v = paint(&truth, prep_samples(pp), &l);
    ASSERT_OK(prep_fit(pp, NULL, v, &m, &e));
    d = saved_and_read_back(&m, &back);
    printf("  read back: largest relative difference %.3g\n", d);
    ASSERT(d >= 0.0);
    ASSERT_LT(d, 1e-12);
    ASSERT(strcmp(material_method_name(&back), "pbr_env") == 0);
    ASSERT(pbr_material_of(&back) != NULL);
    free(v);
    material_free(&m);
    material_free(&back);
    material_free(&truth);
    env_lights_free(&l);
    prep_release(C, pp);
}

/* Fit values v (3 n of the preparation's samples); the material in *m. */
static int fit_values(prep *pp, const float *v, material *m, glint_err *e)
{
    return prep_fit(pp, NULL, v, m, e);
}

TEST(extremes)
{
    pbr_env_params p;
    env_lights l;
    material m, truth;
    glint_err e;
    prep *pp;
    const samples *s;
    float *v;
    long n3;

    ASSERT(setup() == 0);
    params_of(&p);
    ASSERT_OK(lights_of(0.0, p.env.lights, &l));
    ASSERT((pp = prep_of(&p, NULL)) != NULL);
    s = prep_samples(pp);
    n3 = 3L * s->n;
    v = calloc((size_t)n3, sizeof *v);

    /* all black: a black material, its shape undetermined, said so */
    ASSERT_OK(fit_values(pp, v, &m, &e));
    ASSERT_EQ(pbr_material_of(&m)->kd[0], 0.0);
    ASSERT(in_list(&m, "undetermined", "alpha"));
    ASSERT(notes_say(&m, "black"));
    material_free(&m);

    /* one painted pixel */
    v[3 * (s->n / 2)] = v[3 * (s->n / 2) + 1] = v[3 * (s->n / 2) + 2] = 0.5f;
    ASSERT_OK(fit_values(pp, v, &m, &e));
    {
        double f[3], n[3] = {0, 0, 1}, wi[3] = {0, 0.6, 0.8}, wo[3] = {0, -0.6, 0.8};
        material_eval(&m, n, wi, wo, f);
        ASSERT(isfinite(f[0]) && isfinite(f[1]) && isfinite(f[2]));
    }
    material_free(&m);

    /* NaN and inf: refused, the value named */
    v[7] = NAN;
    ASSERT_EQ(fit_values(pp, v, &m, &e), GLINT_ENONFINITE);
    ASSERT(strstr(e.msg, "value 2") != NULL);
    v[7] = INFINITY;
    ASSERT_EQ(fit_values(pp, v, &m, &e), GLINT_ENONFINITE);
    free(v);

    /* a Lambertian: the roughness is undetermined */
    known(&truth, 0.6, 0.5, 0.4, 0.3, 0.0, 1.5);
    v = paint(&truth, s, &l);
    ASSERT_OK(fit_values(pp, v, &m, &e));
    printf("  lambertian: kd %.4f, alpha %s\n", pbr_material_of(&m)->kd[0],
           in_list(&m, "undetermined", "alpha") ? "undetermined" : "determined");
    ASSERT_NEAR(pbr_material_of(&m)->kd[0], 0.6, 0.006);
    ASSERT(in_list(&m, "undetermined", "alpha"));
    material_free(&m);

    /* brighter than physical: diffuse clamped at 1, said so */
    for (long i = 0; i < n3; i++)
        v[i] *= 4.0f;
    ASSERT_OK(fit_values(pp, v, &m, &e));
    ASSERT_EQ(pbr_material_of(&m)->kd[0], 1.0);
    ASSERT(notes_say(&m, "brighter than a physical"));
    material_free(&m);
    material_free(&truth);
    free(v);

    /* a mirror: the roughness at its floor */
    known(&truth, 0.05, 0.05, 0.05, PBR_ALPHA_MIN, 3.0, 1.5);
    v = paint(&truth, s, &l);
    ASSERT_OK(fit_values(pp, v, &m, &e));
    printf("  mirror: alpha %.4g\n", pbr_material_of(&m)->lobe[0].alpha);
    ASSERT_LT(pbr_material_of(&m)->lobe[0].alpha, 0.02);
    material_free(&m);
    material_free(&truth);
    free(v);
    env_lights_free(&l);
    prep_release(C, pp);
}

TEST(one_view_only)
{
    pbr_env_params p;
    env_lights l;
    material truth, m;
    glint_err e;
    prep *pp;
    unsigned char one[SCENE_MAX_VIEWS] = {0};
    float *v;

    ASSERT(setup() == 0);
    params_of(&p);
    ASSERT_OK(lights_of(0.0, p.env.lights, &l));
    known(&truth, 0.3, 0.2, 0.1, 0.2, 1.0, 1.5);
    one[0] = 1;
    ASSERT((pp = prep_of(&p, one)) != NULL);
    v = paint(&truth, prep_samples(pp), &l);
    ASSERT_OK(prep_fit(pp, NULL, v, &m, &e));
    ASSERT_EQ(json_array_size(json_object_get(json_object_get(m.info, "errors"), "rms_by_view")),
              1);
    printf("  one view: kd %.4f, alpha %.4f\n", pbr_material_of(&m)->kd[0],
           pbr_material_of(&m)->lobe[0].alpha);
    ASSERT_NEAR(pbr_material_of(&m)->kd[0], 0.3, 0.01);
    free(v);
    material_free(&m);
    material_free(&truth);
    env_lights_free(&l);
    prep_release(C, pp);
}

TEST_LIST {
    TEST_ENTRY(model_truth_comes_back_and_holds_under_a_turned_environment),
    TEST_ENTRY(prediction_is_the_independent_render),
    TEST_ENTRY(lights_and_rows_are_srbf_levels),
    TEST_ENTRY(material_round_trip),
    TEST_ENTRY(extremes),
    TEST_ENTRY(one_view_only),
};

TEST_MAIN()
