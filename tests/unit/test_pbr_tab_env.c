/* test_pbr_tab_env.c: the pbr_tab_env method (core/methods/pbr_tab_env):
 * pbr_env's fit times a table over half and difference angles, fitted to
 * views painted under an environment.
 *
 * Paintings are rendered here (env_fixture.h), independently of the
 * method's terms and of its solve: at every sample the sum over the sky's
 * median-cut lights of power x f x cos, f the truth's own evaluation.
 *
 *   - a truth the model holds (a pbr base times a smooth table that the
 *     physical fit alone cannot follow): the painted views come back to
 *     within 1%, five times closer than pbr_env's fit, and a view never
 *     painted, under the sky turned 120 degrees, twice as close;
 *   - an exact base leaves the table at 1 and the fit equal to pbr_env's;
 *   - the prediction equals the independent render at every fitted pixel;
 *   - the levels are pbr_env's (the same keys: a pbr_env fit shares them);
 *   - a material saved and read back is this method's pbr_tab material,
 *     evaluating alike;
 *   - held-out samples are never read (their values NaN);
 *   - extremes: all-black (black, said so), one painted pixel, NaN and inf
 *     (refused, named), a Lambertian (table 1, roughness undetermined), a
 *     painting brighter than physical (the base's note carried up), a
 *     mirror (the base's roughness at its floor), one view only. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "env_fixture.h"
#include "method_pbr_tab.h"
#include "method_pbr_tab_env.h"

/* Defaults under the sky, 64 lights. */
static void params_of(pbr_tab_env_params *p)
{
    method_pbr_tab_env.params_default(p);
    snprintf(p->base.env.env, sizeof p->base.env.env, "sky");
    p->base.env.lights = 64;
}

static void base_params_of(pbr_env_params *p)
{
    method_pbr_env.params_default(p);
    snprintf(p->env.env, sizeof p->env.env, "sky");
    p->env.lights = 64;
}

static prep *prep_of(const pbr_tab_env_params *params, const unsigned char *use)
{
    return prep_method(&method_pbr_tab_env, params, use);
}

static const json_t *correction(const material *m)
{
    return json_object_get(m->info, "correction");
}

static int notes_say(const json_t *info, const char *words)
{
    const json_t *a = json_object_get(info, "notes"), *x;
    size_t i;
    json_array_foreach(a, i, x)
        if (strstr(json_string_value(x), words))
            return 1;
    return 0;
}

static int in_list(const json_t *info, const char *list, const char *name)
{
    const json_t *a = json_object_get(info, list), *x;
    size_t i;
    json_array_foreach(a, i, x) {
        const char *s = json_is_string(x) ? json_string_value(x)
                                          : json_string_value(json_object_get(x, "name"));
        if (s && !strcmp(s, name))
            return 1;
    }
    return 0;
}

/* A truth the model holds: the pbr material of `known` times a table that
 * brightens grazing theta_d and dims the highlight's tail, per channel
 * differently (multiply). */
static void truth_with_table(material *m)
{
    material base;
    tab_material t = {{32, 16}, NULL};
    glint_err e;
    known(&base, 0.3, 0.25, 0.2, 0.2, 1.0, 1.5);
    t.t = malloc(3 * sizeof(double) * (size_t)tab_nodes(&t.g));
    for (int j = 0; j < t.g.res_d; j++)
        for (int i = 0; i < t.g.res_h; i++) {
            double u = (double)i / (t.g.res_h - 1), v = (double)j / (t.g.res_d - 1);
            for (int c = 0; c < 3; c++)
                t.t[3 * (size_t)(j * t.g.res_h + i) + c] =
                    1.0 + (0.6 + 0.2 * c) * v * v - 0.3 * u * (1.0 - 0.3 * c);
        }
    if (pbr_tab_material_init(m, pbr_material_of(&base), &t, PBR_TAB_MULTIPLY, json_object(),
                              &e))
        abort();
    material_free(&base);
}

TEST(a_truth_the_table_multiplies_comes_back_where_the_physical_fit_alone_does_not)
{
    pbr_tab_env_params p;
    pbr_env_params pb;
    env_lights l, lr;
    material truth, m, mb;
    glint_err e;
    prep *pp, *pn, *ppb;
    unsigned char other[SCENE_MAX_VIEWS] = {0};
    float *v, *t, *r, *rb, *back, *backb;
    double ep, epb, en, enb;

    ASSERT(setup() == 0);
    params_of(&p);
    base_params_of(&pb);
    ASSERT_OK(lights_of(0.0, 64, &l));
    ASSERT_OK(lights_of(120.0, 64, &lr));
    truth_with_table(&truth);
    ASSERT((pp = prep_of(&p, NULL)) != NULL);
    ASSERT((ppb = prep_method(&method_pbr_env, &pb, NULL)) != NULL);
    ASSERT((v = paint(&truth, prep_samples(pp), &l)) != NULL);
    ASSERT_OK(prep_fit(pp, NULL, v, &m, &e));
    ASSERT_OK(prep_fit(ppb, NULL, v, &mb, &e));
    ASSERT(strcmp(material_method_name(&m), "pbr_tab_env") == 0);
    back = paint(&m, prep_samples(pp), &l);
    backb = paint(&mb, prep_samples(pp), &l);
    ep = rel_diff(back, v, 3L * prep_samples(pp)->n);
    epb = rel_diff(backb, v, 3L * prep_samples(pp)->n);
    other[1] = 1;
    ASSERT((pn = prep_of(&p, other)) != NULL);
    t = paint(&truth, prep_samples(pn), &lr);
    r = paint(&m, prep_samples(pn), &lr);
    rb = paint(&mb, prep_samples(pn), &lr);
    en = rel_diff(r, t, 3L * prep_samples(pn)->n);
    enb = rel_diff(rb, t, 3L * prep_samples(pn)->n);
    printf("  painted: %.4f (pbr_env %.4f); view 1 under the sky turned 120 degrees: %.4f "
           "(pbr_env %.4f); %d of %d nodes reached\n",
           ep, epb, en, enb, (int)json_integer_value(json_object_get(correction(&m), "reached")),
           (int)json_integer_value(json_object_get(correction(&m), "nodes")));
    ASSERT_LT(ep, 0.01);
    ASSERT_LT(5.0 * ep, epb);
    ASSERT_LT(2.0 * en, enb);
    ASSERT(json_is_object(json_object_get(m.info, "base")));
    free(t);
    free(r);
    free(rb);
    free(back);
    free(backb);
    free(v);
    material_free(&m);
    material_free(&mb);
    material_free(&truth);
    env_lights_free(&l);
    env_lights_free(&lr);
    prep_release(C, pp);
    prep_release(C, ppb);
    prep_release(C, pn);
}

TEST(an_exact_base_leaves_the_table_at_one)
{
    pbr_tab_env_params p;
    env_lights l;
    material truth, m;
    glint_err e;
    prep *pp;
    float *v, *back;
    const json_t *rg;

    ASSERT(setup() == 0);
    params_of(&p);
    ASSERT_OK(lights_of(0.0, 64, &l));
    known(&truth, 0.3, 0.2, 0.1, 0.25, 0.8, 1.5);
    ASSERT((pp = prep_of(&p, NULL)) != NULL);
    v = paint(&truth, prep_samples(pp), &l);
    ASSERT_OK(prep_fit(pp, NULL, v, &m, &e));
    back = paint(&m, prep_samples(pp), &l);
    rg = json_object_get(correction(&m), "range");
    printf("  table over the reached nodes: %.5f .. %.5f; painted error %.3g\n",
           json_number_value(json_array_get(json_object_get(rg, "min"), 0)),
           json_number_value(json_array_get(json_object_get(rg, "max"), 0)),
           rel_diff(back, v, 3L * prep_samples(pp)->n));
    for (int c = 0; c < 3; c++) {
        ASSERT_NEAR(json_number_value(json_array_get(json_object_get(rg, "min"), c)), 1.0, 0.02);
        ASSERT_NEAR(json_number_value(json_array_get(json_object_get(rg, "max"), c)), 1.0, 0.02);
    }
    ASSERT_LT(rel_diff(back, v, 3L * prep_samples(pp)->n), 1e-3);
    free(back);
    free(v);
    material_free(&m);
    material_free(&truth);
    env_lights_free(&l);
    prep_release(C, pp);
}

/* The truth of truth_with_table painted under the sky's 64 lights (OUT l,
 * truth) on views 0, 4 and 8, and fitted at params_of's (OUT pp, m). */
static int fit_table_truth(env_lights *l, material *truth, prep **pp, material *m)
{
    pbr_tab_env_params p;
    glint_err e;
    float *v;
    int rc;
    if (setup() || lights_of(0.0, 64, l))
        return -1;
    params_of(&p);
    truth_with_table(truth);
    if (!(*pp = prep_of(&p, NULL)) || !(v = paint(truth, prep_samples(*pp), l)))
        return -1;
    rc = prep_fit(*pp, NULL, v, m, &e);
    free(v);
    return rc;
}

TEST(prediction_is_the_independent_render)
{
    env_lights l;
    material truth, m;
    prep *pp = NULL;
    long fitted;
    double d;

    ASSERT_OK(fit_table_truth(&l, &truth, &pp, &m));
    d = predicted_vs_render(pp, &m, &l, &fitted);
    printf("  %ld values predicted, relative difference %.3g\n", fitted, d);
    ASSERT(fitted > 0);
    ASSERT(d >= 0.0);
    ASSERT_LT(d, 1e-5);
    material_free(&m);
    material_free(&truth);
    env_lights_free(&l);
    prep_release(C, pp);
}

TEST(levels_are_pbr_envs)
{
    pbr_tab_env_params p;
    char a[256], b[256];
    ASSERT(setup() == 0);
    params_of(&p);
    for (int k = 0; k < 1; k++) { /* the first from its params alone */
        method_pbr_tab_env.levels[k].key(&p, NULL, "x", a, sizeof a);
        method_pbr_env.levels[k].key(&p.base, NULL, "x", b, sizeof b);
        ASSERT(strcmp(a, b) == 0);
    }
    ASSERT_EQ(method_pbr_tab_env.nlevels, method_pbr_env.nlevels);
    {
        prep *pp = prep_of(&p, NULL);
        const samples *s;
        ASSERT(pp != NULL);
        s = prep_samples(pp);
        for (int k = 1; k < method_pbr_env.nlevels; k++) {
            method_pbr_tab_env.levels[k].key(&p, s, "prev", a, sizeof a);
            method_pbr_env.levels[k].key(&p.base, s, "prev", b, sizeof b);
            ASSERT(strcmp(a, b) == 0);
        }
        prep_release(C, pp);
    }
}

TEST(material_round_trip)
{
    env_lights l;
    material truth, m, back;
    prep *pp = NULL;
    double d;

    ASSERT_OK(fit_table_truth(&l, &truth, &pp, &m));
    d = saved_and_read_back(&m, &back);
    printf("  read back: largest relative difference %.3g\n", d);
    ASSERT(d >= 0.0);
    ASSERT_LT(d, 1e-12);
    ASSERT(strcmp(material_method_name(&back), "pbr_tab_env") == 0);
    ASSERT(pbr_tab_material_of(&back) != NULL);
    ASSERT_EQ(pbr_tab_material_of(&back)->combine, PBR_TAB_MULTIPLY);
    material_free(&m);
    material_free(&back);
    material_free(&truth);
    env_lights_free(&l);
    prep_release(C, pp);
}

TEST(held_out_values_are_never_read)
{
    pbr_tab_env_params p;
    env_lights l;
    material truth, a, b;
    glint_err e;
    prep *pp;
    const samples *s;
    unsigned char *held;
    float *v;
    double fa[3], fb[3], n[3] = {0, 0, 1}, wi[3] = {0.5, 0, 0.866025}, wo[3] = {-0.2, 0, 0.979796};

    ASSERT(setup() == 0);
    params_of(&p);
    ASSERT_OK(lights_of(0.0, 64, &l));
    truth_with_table(&truth);
    ASSERT((pp = prep_of(&p, NULL)) != NULL);
    s = prep_samples(pp);
    v = paint(&truth, s, &l);
    held = calloc((size_t)s->n, 1);
    for (int i = 0; i < s->n; i++)
        held[i] = s->view[i] == 8;
    ASSERT_OK(prep_fit_held(pp, v, held, &a, &e));
    for (int i = 0; i < s->n; i++)
        if (held[i])
            v[3 * i] = v[3 * i + 1] = v[3 * i + 2] = NAN;
    ASSERT_OK(prep_fit_held(pp, v, held, &b, &e));
    ASSERT(json_integer_value(json_object_get(a.info, "rows_held_out")) > 0);
    material_eval(&a, n, wi, wo, fa);
    material_eval(&b, n, wi, wo, fb);
    for (int c = 0; c < 3; c++)
        ASSERT_EQ(fa[c], fb[c]);
    free(held);
    free(v);
    material_free(&a);
    material_free(&b);
    material_free(&truth);
    env_lights_free(&l);
    prep_release(C, pp);
}

TEST(extremes)
{
    pbr_tab_env_params p;
    env_lights l;
    material m, truth;
    glint_err e;
    prep *pp;
    const samples *s;
    float *v;
    long n3;

    ASSERT(setup() == 0);
    params_of(&p);
    ASSERT_OK(lights_of(0.0, 64, &l));
    ASSERT((pp = prep_of(&p, NULL)) != NULL);
    s = prep_samples(pp);
    n3 = 3L * s->n;
    v = calloc((size_t)n3, sizeof *v);

    /* all black: a black material, said so; the table has nothing to scale */
    ASSERT_OK(prep_fit(pp, NULL, v, &m, &e));
    ASSERT_EQ(pbr_tab_material_of(&m)->base.kd[0], 0.0);
    ASSERT(notes_say(m.info, "black"));
    ASSERT_EQ(json_integer_value(
                  json_array_get(json_object_get(json_object_get(correction(&m), "solve"),
                                                 "base_black"), 0)),
              1);
    material_free(&m);

    /* one painted pixel: a finite material */
    v[3 * (s->n / 2)] = v[3 * (s->n / 2) + 1] = v[3 * (s->n / 2) + 2] = 0.5f;
    ASSERT_OK(prep_fit(pp, NULL, v, &m, &e));
    {
        double f[3], n[3] = {0, 0, 1}, wi[3] = {0, 0.6, 0.8}, wo[3] = {0, -0.6, 0.8};
        material_eval(&m, n, wi, wo, f);
        ASSERT(isfinite(f[0]) && isfinite(f[1]) && isfinite(f[2]));
    }
    material_free(&m);

    /* NaN and inf: refused, the value named */
    v[7] = NAN;
    ASSERT_EQ(prep_fit(pp, NULL, v, &m, &e), GLINT_ENONFINITE);
    ASSERT(strstr(e.msg, "value 2") != NULL);
    v[7] = INFINITY;
    ASSERT_EQ(prep_fit(pp, NULL, v, &m, &e), GLINT_ENONFINITE);
    free(v);

    /* a Lambertian: the table stays at 1, the roughness undetermined */
    known(&truth, 0.6, 0.5, 0.4, 0.3, 0.0, 1.5);
    v = paint(&truth, s, &l);
    ASSERT_OK(prep_fit(pp, NULL, v, &m, &e));
    printf("  lambertian: kd %.4f, table max %.4f\n", pbr_tab_material_of(&m)->base.kd[0],
           json_number_value(json_array_get(
               json_object_get(json_object_get(correction(&m), "range"), "max"), 0)));
    ASSERT_NEAR(pbr_tab_material_of(&m)->base.kd[0], 0.6, 0.006);
    ASSERT(in_list(json_object_get(m.info, "base"), "undetermined", "alpha"));
    ASSERT_NEAR(json_number_value(json_array_get(
                    json_object_get(json_object_get(correction(&m), "range"), "max"), 0)),
                1.0, 0.02);
    material_free(&m);

    /* brighter than physical: the base's diffuse clamped at 1, said at the top */
    for (long i = 0; i < n3; i++)
        v[i] *= 4.0f;
    ASSERT_OK(prep_fit(pp, NULL, v, &m, &e));
    ASSERT_EQ(pbr_tab_material_of(&m)->base.kd[0], 1.0);
    ASSERT(notes_say(m.info, "brighter than a physical"));
    material_free(&m);
    material_free(&truth);
    free(v);

    /* a mirror: the base's roughness at its floor */
    known(&truth, 0.05, 0.05, 0.05, PBR_ALPHA_MIN, 3.0, 1.5);
    v = paint(&truth, s, &l);
    ASSERT_OK(prep_fit(pp, NULL, v, &m, &e));
    printf("  mirror: alpha %.4g\n", pbr_tab_material_of(&m)->base.lobe[0].alpha);
    ASSERT_LT(pbr_tab_material_of(&m)->base.lobe[0].alpha, 0.02);
    material_free(&m);
    material_free(&truth);
    free(v);
    env_lights_free(&l);
    prep_release(C, pp);
}

TEST(one_view_only)
{
    pbr_tab_env_params p;
    env_lights l;
    material truth, m;
    glint_err e;
    prep *pp;
    unsigned char one[SCENE_MAX_VIEWS] = {0};
    float *v, *back;

    ASSERT(setup() == 0);
    params_of(&p);
    ASSERT_OK(lights_of(0.0, 64, &l));
    truth_with_table(&truth);
    one[0] = 1;
    ASSERT((pp = prep_of(&p, one)) != NULL);
    v = paint(&truth, prep_samples(pp), &l);
    ASSERT_OK(prep_fit(pp, NULL, v, &m, &e));
    back = paint(&m, prep_samples(pp), &l);
    ASSERT_EQ(json_array_size(json_object_get(json_object_get(m.info, "errors"), "rms_by_view")),
              1);
    printf("  one view: painted error %.4f\n", rel_diff(back, v, 3L * prep_samples(pp)->n));
    ASSERT_LT(rel_diff(back, v, 3L * prep_samples(pp)->n), 0.02);
    free(back);
    free(v);
    material_free(&m);
    material_free(&truth);
    env_lights_free(&l);
    prep_release(C, pp);
}

TEST_LIST {
    TEST_ENTRY(a_truth_the_table_multiplies_comes_back_where_the_physical_fit_alone_does_not),
    TEST_ENTRY(an_exact_base_leaves_the_table_at_one),
    TEST_ENTRY(prediction_is_the_independent_render),
    TEST_ENTRY(levels_are_pbr_envs),
    TEST_ENTRY(material_round_trip),
    TEST_ENTRY(held_out_values_are_never_read),
    TEST_ENTRY(extremes),
    TEST_ENTRY(one_view_only),
};

TEST_MAIN()
