/* test_auto_env.c: fits that leave samples out (method_fit_in.held, for
 * pbr_env and srbf), the held-out measurement on one preparation that
 * they allow (prep_holdout), and the auto_env method that chooses among
 * the models fitted under an environment (core/methods/auto).
 *
 * Paintings are rendered here (env_fixture.h), independently of the
 * methods' terms and transfer.
 *
 *   - a fit that holds view 8 out never reads its values (junk there
 *     gives the same material to the bit), and equals the fit of a
 *     preparation of the other views alone (pbr_env to 1e-9, srbf's
 *     weights to 1e-9 of the largest: its Gram matrix is the full one less
 *     the held rows' part, summed in another order);
 *   - prep_holdout on one preparation gives for each view the error that
 *     the fold's own preparation and a prediction of the view alone give;
 *   - auto_env reports its six candidates, each measured on the held-out
 *     views of its two hold-outs (other views in each), takes the first unless a later one gains the threshold, never
 *     answers worse there than the first, and its material renders the
 *     truth on the held-out view;
 *   - a painting of two lobes takes the two-lobe candidate;
 *   - extremes: one view only (its right and then its left band held out,
 *     counted here from the pixels; srbf not tried), two views (each held
 *     out in turn), all-black, a single painted pixel, NaN (refused, named). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "env_fixture.h"
#include "img.h"
#include "method_auto_env.h"
#include "method_srbf.h"

#define LIGHTS 64

static void pbr_env_of(pbr_env_params *p)
{
    method_pbr_env.params_default(p);
    snprintf(p->env.env, sizeof p->env.env, "sky");
    p->env.lights = LIGHTS;
}

static void srbf_of(srbf_params *p)
{
    method_srbf.params_default(p);
    snprintf(p->env, sizeof p->env, "sky");
    p->lights = LIGHTS;
}

static void auto_env_of(auto_env_params *p)
{
    method_auto_env.params_default(p);
    snprintf(p->env.env, sizeof p->env.env, "sky");
    p->env.lights = LIGHTS;
}

/* 1 at the samples of view k (malloc'ed, n). */
static unsigned char *view_mask(const samples *s, int k)
{
    unsigned char *h = malloc((size_t)(s->n ? s->n : 1));
    for (int i = 0; h && i < s->n; i++)
        h[i] = s->view[i] == k;
    return h;
}

/* The rows of a fit's report that were held out. */
static long rows_held(const material *m)
{
    const json_t *a = json_object_get(m->info, "rows_held_out");
    if (!a)
        a = json_object_get(json_object_get(m->info, "errors"), "rows_held_out");
    return json_is_integer(a) ? (long)json_integer_value(a) : -1;
}

TEST(pbr_env_leaves_held_samples_out)
{
    pbr_env_params p;
    env_lights l;
    material truth, m1, m2, m3;
    glint_err e;
    prep *pp, *p2;
    unsigned char two[SCENE_MAX_VIEWS] = {0}, *held;
    float *v, *junk, *v2;
    const samples *s;
    const pbr_material *a, *b, *c;

    ASSERT(setup() == 0);
    pbr_env_of(&p);
    ASSERT_OK(lights_of(0.0, LIGHTS, &l));
    known(&truth, 0.3, 0.2, 0.1, 0.2, 1.0, 1.5);
    ASSERT((pp = prep_method(&method_pbr_env, &p, NULL)) != NULL);
    s = prep_samples(pp);
    v = paint(&truth, s, &l);
    held = view_mask(s, 8);
    junk = malloc(3 * sizeof(float) * (size_t)s->n);
    for (long i = 0; i < 3L * s->n; i++)
        junk[i] = held[i / 3] ? (i % 7 ? 5.0f : NAN) : v[i];
    ASSERT_OK(prep_fit_held(pp, v, held, &m1, &e));
    ASSERT_OK(prep_fit_held(pp, junk, held, &m2, &e));
    a = pbr_material_of(&m1);
    b = pbr_material_of(&m2);
    ASSERT(a && b);
    ASSERT(memcmp(a->p, b->p, sizeof a->p[0] * (size_t)pbr_np(&a->sp)) == 0);
    ASSERT(rows_held(&m1) > 0);
    /* the preparation of views 0 and 4 alone */
    two[0] = two[4] = 1;
    ASSERT((p2 = prep_method(&method_pbr_env, &p, two)) != NULL);
    v2 = paint(&truth, prep_samples(p2), &l);
    ASSERT_OK(prep_fit(p2, NULL, v2, &m3, &e));
    c = pbr_material_of(&m3);
    printf("  held out %ld rows; kd %.6f alpha %.6f, the two views alone kd %.6f alpha %.6f\n",
           rows_held(&m1), a->kd[0], a->lobe[0].alpha, c->kd[0], c->lobe[0].alpha);
    for (int k = 0; k < pbr_np(&a->sp); k++)
        ASSERT_NEAR(a->p[k], c->p[k], 1e-9 * fmax(1.0, fabs(c->p[k])));
    free(v);
    free(v2);
    free(junk);
    free(held);
    material_free(&m1);
    material_free(&m2);
    material_free(&m3);
    material_free(&truth);
    env_lights_free(&l);
    prep_release(C, pp);
    prep_release(C, p2);
}

TEST(srbf_leaves_held_samples_out)
{
    srbf_params p;
    env_lights l;
    material truth, m1, m2, m3;
    glint_err e;
    prep *pp, *p2;
    unsigned char two[SCENE_MAX_VIEWS] = {0}, *held;
    float *v, *junk, *v2;
    const samples *s;
    const srbf_material *a, *b, *c;
    double big = 0.0, diff = 0.0;

    ASSERT(setup() == 0);
    srbf_of(&p);
    ASSERT_OK(lights_of(0.0, LIGHTS, &l));
    known(&truth, 0.3, 0.2, 0.1, 0.2, 1.0, 1.5);
    ASSERT((pp = prep_method(&method_srbf, &p, NULL)) != NULL);
    s = prep_samples(pp);
    v = paint(&truth, s, &l);
    held = view_mask(s, 8);
    junk = malloc(3 * sizeof(float) * (size_t)s->n);
    for (long i = 0; i < 3L * s->n; i++)
        junk[i] = held[i / 3] ? 5.0f : v[i];
    ASSERT_OK(prep_fit_held(pp, v, held, &m1, &e));
    ASSERT_OK(prep_fit_held(pp, junk, held, &m2, &e));
    a = srbf_material_of(&m1);
    b = srbf_material_of(&m2);
    ASSERT(a && b && a->b.J == b->b.J);
    ASSERT(memcmp(a->c, b->c, 3 * sizeof(double) * (size_t)a->b.J) == 0);
    ASSERT(memcmp(a->rho, b->rho, sizeof a->rho) == 0);
    ASSERT(rows_held(&m1) > 0);
    two[0] = two[4] = 1;
    ASSERT((p2 = prep_method(&method_srbf, &p, two)) != NULL);
    v2 = paint(&truth, prep_samples(p2), &l);
    ASSERT_OK(prep_fit(p2, NULL, v2, &m3, &e));
    c = srbf_material_of(&m3);
    ASSERT(c && c->b.J == a->b.J);
    for (int k = 0; k < 3 * a->b.J; k++) {
        big = fmax(big, fabs(c->c[k]));
        diff = fmax(diff, fabs(a->c[k] - c->c[k]));
    }
    printf("  held out %ld rows; lobe weights differ from the two views' fit by %.3g of the "
           "largest (%.4g); diffuse %.6f against %.6f\n",
           rows_held(&m1), diff / big, big, a->rho[0], c->rho[0]);
    ASSERT(big > 0.0);
    ASSERT_LT(diff, 1e-9 * big);
    for (int ch = 0; ch < 3; ch++)
        ASSERT_NEAR(a->rho[ch], c->rho[ch], 1e-9);
    free(v);
    free(v2);
    free(junk);
    free(held);
    material_free(&m1);
    material_free(&m2);
    material_free(&m3);
    material_free(&truth);
    env_lights_free(&l);
    prep_release(C, pp);
    prep_release(C, p2);
}

/* A pbr material of two lobes: a sharp highlight over a broad sheen (one
 * lobe does not model it). */
static void two_lobes(material *m)
{
    pbr_material *pm = calloc(1, sizeof *pm);
    pm->sp.nlobes = 2;
    pm->sp.fresnel = PBR_DIELECTRIC;
    pm->p[0] = 0.2, pm->p[1] = 0.15, pm->p[2] = 0.1;
    pm->p[3] = 0.08, pm->p[4] = pm->p[5] = pm->p[6] = 1.0, pm->p[7] = 1.5;
    pm->p[8] = 0.4, pm->p[9] = pm->p[10] = pm->p[11] = 1.5, pm->p[12] = 1.5;
    pbr_material_sync(pm);
    material_init(m, &method_pbr_env, pm, json_object());
}

/* Paintings of the scene's views from per-sample values v of s (radiance:
 * v times the intensity), zero elsewhere (OUT: im[SC.nviews]). */
static int paintings_of(const samples *s, const float *v, img *im)
{
    for (int k = 0; k < SC.nviews; k++) {
        im[k].width = s->width;
        im[k].height = s->height;
        im[k].channels = 3;
        if (!(im[k].px = calloc((size_t)3 * s->width * s->height, sizeof(float))))
            return -1;
    }
    for (int i = 0; i < s->n; i++)
        for (int c = 0; c < 3; c++)
            im[s->view[i]].px[3 * (size_t)s->pixel[i] + c] =
                (float)(v[3 * (size_t)i + c] * s->intensity[i]);
    return 0;
}

/* The error prep_holdout's fold path gives view k: a fit of the other
 * views' own preparation, predicted on a preparation of view k alone. */
static double fold_rms(const pbr_env_params *p, const material *truth, const env_lights *l,
                       int k)
{
    unsigned char rest[SCENE_MAX_VIEWS] = {0}, one[SCENE_MAX_VIEWS] = {0};
    prep *pr, *po;
    material m;
    glint_err e;
    float *v, *t, *pred;
    const samples *s;
    double ss = 0.0;
    long cnt = 0;
    for (int j = 0; j < 3; j++)
        rest[4 * j] = 4 * j != k;
    one[k] = 1;
    pr = prep_method(&method_pbr_env, p, rest);
    po = prep_method(&method_pbr_env, p, one);
    if (!pr || !po)
        return -1.0;
    v = paint(truth, prep_samples(pr), l);
    if (prep_fit(pr, NULL, v, &m, &e))
        return -1.0;
    s = prep_samples(po);
    t = paint(truth, s, l);
    pred = malloc(3 * sizeof(float) * (size_t)s->n);
    if (!prep_predict(po, &m, pred, &e))
        for (int i = 0; i < s->n; i++) {
            if (isnan(pred[3 * (size_t)i]))
                continue;
            for (int c = 0; c < 3; c++) {
                double d = pred[3 * (size_t)i + c] - t[3 * (size_t)i + c] * s->intensity[i];
                ss += d * d;
            }
            cnt++;
        }
    free(v);
    free(t);
    free(pred);
    material_free(&m);
    prep_release(C, pr);
    prep_release(C, po);
    return cnt ? sqrt(ss / (3.0 * cnt)) : -1.0;
}

TEST(holdout_on_one_preparation_is_the_folds)
{
    pbr_env_params p;
    env_lights l;
    material truth;
    glint_err e;
    prep *pp;
    img im[SCENE_MAX_VIEWS];
    float *v;
    json_t *res = NULL, *x;
    size_t i;

    ASSERT(setup() == 0);
    memset(im, 0, sizeof im);
    pbr_env_of(&p);
    ASSERT_OK(lights_of(0.0, LIGHTS, &l));
    /* two lobes, fitted by one: an error worth comparing */
    two_lobes(&truth);
    ASSERT((pp = prep_method(&method_pbr_env, &p, NULL)) != NULL);
    v = paint(&truth, prep_samples(pp), &l);
    ASSERT_OK(paintings_of(prep_samples(pp), v, im));
    ASSERT_OK(prep_holdout(&method_pbr_env, &p, prep_samples(pp), im, NULL, NULL, NULL, NULL,
                           &res, &e));
    ASSERT_EQ(json_array_size(json_object_get(res, "per_view")), 3);
    json_array_foreach(json_object_get(res, "per_view"), i, x) {
        int k = (int)json_integer_value(json_object_get(x, "view"));
        double got = json_number_value(json_object_get(x, "rms"));
        double want = fold_rms(&p, &truth, &l, k);
        printf("  view %d: held out on one preparation %.6g, the fold's own %.6g\n", k, got,
               want);
        ASSERT(want >= 0.0);
        ASSERT_NEAR(got, want, 1e-6 * fmax(want, 1e-3));
    }
    json_decref(res);
    for (int k = 0; k < SCENE_MAX_VIEWS; k++)
        free(im[k].px);
    free(v);
    material_free(&truth);
    env_lights_free(&l);
    prep_release(C, pp);
}

/* auto_env's choice: its candidates and the index of the chosen one. */
static const json_t *choice_of(const material *m)
{
    return json_object_get(m->info, "choice");
}

static double cand_num(const material *m, int c, const char *name)
{
    return json_number_value(
        json_object_get(json_array_get(json_object_get(choice_of(m), "candidates"), c), name));
}

static int chosen_index(const material *m)
{
    const json_t *a = json_object_get(choice_of(m), "candidates"), *x;
    size_t i;
    int k = -1;
    json_array_foreach(a, i, x)
        if (json_is_true(json_object_get(x, "taken")))
            k = (int)i;
    return k;
}

/* auto_env at p fitted to truth painted under the sky's lights. */
static int auto_fit_at(const auto_env_params *p, const material *truth, const unsigned char *use,
                       material *m, prep **pp, glint_err *e)
{
    env_lights l;
    float *v;
    int rc;
    if (lights_of(0.0, p->env.lights, &l) ||
        !(*pp = prep_method(&method_auto_env, p, use)))
        return -1;
    v = paint(truth, prep_samples(*pp), &l);
    rc = prep_fit(*pp, NULL, v, m, e);
    free(v);
    env_lights_free(&l);
    return rc;
}

/* auto_env at its defaults. */
static int auto_fit(const material *truth, const unsigned char *use, material *m, prep **pp,
                    glint_err *e)
{
    auto_env_params p;
    auto_env_of(&p);
    return auto_fit_at(&p, truth, use, m, pp, e);
}

static const char *choice_str(const material *m, const char *key)
{
    const char *v = json_string_value(json_object_get(choice_of(m), key));
    return v ? v : "";
}

static const char *cand_str(const material *m, int c, const char *key)
{
    const char *v = json_string_value(
        json_object_get(json_array_get(json_object_get(choice_of(m), "candidates"), c), key));
    return v ? v : "";
}

TEST(auto_env_chooses_and_reports)
{
    material truth, m;
    glint_err e;
    prep *pp = NULL;
    const json_t *ch;
    int k;

    ASSERT(setup() == 0);
    known(&truth, 0.3, 0.2, 0.1, 0.15, 1.0, 1.5);
    ASSERT_OK(auto_fit(&truth, NULL, &m, &pp, &e));
    ch = choice_of(&m);
    ASSERT(ch != NULL);
    ASSERT_EQ(json_array_size(json_object_get(ch, "candidates")), 6);
    ASSERT(!strcmp(json_string_value(json_object_get(ch, "held_out")), "views"));
    ASSERT_EQ(json_integer_value(json_array_get(json_object_get(ch, "held_out_views"), 0)), 8);
    /* two hold-outs (the default): the views of the first, then others */
    {
        const json_t *f = json_object_get(ch, "held_out_folds"), *a, *b;
        size_t i, j;
        ASSERT_EQ(json_array_size(f), 2);
        a = json_array_get(f, 0);
        b = json_array_get(f, 1);
        ASSERT(json_equal(a, json_object_get(ch, "held_out_views")));
        ASSERT(json_array_size(b) >= 1);
        for (i = 0; i < json_array_size(a); i++)
            for (j = 0; j < json_array_size(b); j++)
                ASSERT(json_integer_value(json_array_get(a, i)) !=
                       json_integer_value(json_array_get(b, j)));
        char *txt = json_dumps(f, JSON_COMPACT);
        printf("  hold-outs: views %s\n", txt ? txt : "?");
        free(txt);
    }
    k = chosen_index(&m);
    for (int c = 0; c < 6; c++) {
        printf("  %-58s held out %.5g painted %.5g %s\n",
               json_string_value(json_object_get(
                   json_array_get(json_object_get(ch, "candidates"), c), "label")),
               cand_num(&m, c, "held_out_rms"), cand_num(&m, c, "rms_painted"),
               c == k ? "(chosen)" : "");
        ASSERT(cand_num(&m, c, "held_out_rms") >= 0.0);
        ASSERT(cand_num(&m, c, "held_out_samples") > 0);
    }
    ASSERT(json_is_true(json_object_get(json_array_get(json_object_get(ch, "candidates"), 0),
                                        "taken")));
    ASSERT(cand_num(&m, k, "held_out_rms") <= cand_num(&m, 0, "held_out_rms"));
    ASSERT(!strcmp(json_string_value(json_object_get(ch, "chosen")),
                   k == 5 ? "srbf" : k >= 3 ? "pbr_tab_env" : "pbr_env"));
    ASSERT(json_object_get(m.info, "chosen_params") != NULL);
    /* the truth is pbr_env's model: a pbr material, its diffuse back */
    ASSERT(pbr_material_of(&m) != NULL);
    printf("  chose %d: kd %.4f alpha %.4f\n", k, pbr_material_of(&m)->kd[0],
           pbr_material_of(&m)->lobe[0].alpha);
    ASSERT_NEAR(pbr_material_of(&m)->kd[0], 0.3, 0.01);
    material_free(&m);
    material_free(&truth);
    prep_release(C, pp);
}

TEST(two_lobes_take_the_two_lobe_candidate)
{
    material truth, m;
    glint_err e;
    prep *pp = NULL;
    two_lobes(&truth);
    ASSERT(setup() == 0);
    ASSERT_OK(auto_fit(&truth, NULL, &m, &pp, &e));
    for (int c = 0; c < 6; c++)
        printf("  candidate %d held out %.5g painted %.5g\n", c, cand_num(&m, c, "held_out_rms"), cand_num(&m, c, "rms_painted"));
    ASSERT_EQ(chosen_index(&m), 2);
    ASSERT_EQ(pbr_material_of(&m)->sp.nlobes, 2);
    material_free(&m);
    material_free(&truth);
    prep_release(C, pp);
}

/* From one view the choice starts from the correction on two lobes
 * (candidate 4) where its held-out RMS is no worse than the simplest's;
 * with `start` simplest, or from three views, from the simplest. */
TEST(one_view_starts_from_the_correction)
{
    auto_env_params p;
    material truth, m;
    glint_err e;
    prep *pp = NULL;
    unsigned char one[SCENE_MAX_VIEWS] = {0};
    int k;

    ASSERT(setup() == 0);
    two_lobes(&truth);
    one[4] = 1;
    auto_env_of(&p);
    ASSERT_EQ(p.start, AUTO_ENV_START_VIEWS);
    ASSERT_OK(auto_fit_at(&p, &truth, one, &m, &pp, &e));
    printf("  one view: simplest held out %.5g, correction %.5g; started from %s, chose %s\n",
           cand_num(&m, 0, "held_out_rms"), cand_num(&m, 4, "held_out_rms"),
           choice_str(&m, "started_from"), choice_str(&m, "chosen_label"));
    ASSERT(!strcmp(choice_str(&m, "start"), "views"));
    /* a two-lobe truth: the correction on two lobes holds out better */
    ASSERT(cand_num(&m, 4, "held_out_rms") <= cand_num(&m, 0, "held_out_rms"));
    ASSERT(!strcmp(choice_str(&m, "started_from"), cand_str(&m, 4, "label")));
    ASSERT(json_is_true(json_object_get(
        json_array_get(json_object_get(choice_of(&m), "candidates"), 4), "taken")));
    k = chosen_index(&m);
    ASSERT(cand_num(&m, k, "held_out_rms") <= cand_num(&m, 4, "held_out_rms"));
    /* a candidate other than the start is taken only by beating it by the threshold */
    if (k != 4)
        ASSERT(cand_num(&m, k, "held_out_rms") <
               cand_num(&m, 4, "held_out_rms") * (1.0 - p.threshold));
    material_free(&m);
    prep_release(C, pp);

    p.start = AUTO_ENV_START_SIMPLEST;
    ASSERT_OK(auto_fit_at(&p, &truth, one, &m, &pp, &e));
    ASSERT(!strcmp(choice_str(&m, "start"), "simplest"));
    ASSERT(!strcmp(choice_str(&m, "started_from"), cand_str(&m, 0, "label")));
    ASSERT(json_is_true(json_object_get(
        json_array_get(json_object_get(choice_of(&m), "candidates"), 0), "taken")));
    material_free(&m);
    prep_release(C, pp);

    /* three views at the defaults: the simplest */
    auto_env_of(&p);
    ASSERT_OK(auto_fit_at(&p, &truth, NULL, &m, &pp, &e));
    ASSERT(!strcmp(choice_str(&m, "started_from"), cand_str(&m, 0, "label")));
    material_free(&m);
    material_free(&truth);
    prep_release(C, pp);
}

TEST(extremes)
{
    auto_env_params p;
    material truth, m;
    glint_err e;
    prep *pp;
    unsigned char one[SCENE_MAX_VIEWS] = {0};
    const samples *s;
    float *v;

    ASSERT(setup() == 0);
    auto_env_of(&p);
    /* one view: pixel tiles held out */
    known(&truth, 0.3, 0.2, 0.1, 0.2, 1.0, 1.5);
    one[4] = 1;
    ASSERT_OK(auto_fit(&truth, one, &m, &pp, &e));
    ASSERT(!strcmp(json_string_value(json_object_get(choice_of(&m), "held_out")), "pixels"));
    /* its right and left bands, a quarter of its covered columns each */
    {
        const json_t *f = json_object_get(choice_of(&m), "held_out_folds");
        const samples *s1 = prep_samples(pp);
        int lo = s1->width, hi = -1, band;
        long want = 0;
        ASSERT_EQ(json_array_size(f), 2);
        ASSERT(!strcmp(json_string_value(json_array_get(f, 0)), "right"));
        ASSERT(!strcmp(json_string_value(json_array_get(f, 1)), "left"));
        for (int i = 0; i < s1->n; i++) {
            int x = s1->pixel[i] % s1->width;
            lo = x < lo ? x : lo;
            hi = x > hi ? x : hi;
        }
        band = (hi - lo + 1) / p.every;
        ASSERT(band >= 1);
        for (int i = 0; i < s1->n; i++) {
            int x = s1->pixel[i] % s1->width;
            want += (x > hi - band) + (x < lo + band);
        }
        ASSERT_EQ(json_integer_value(json_object_get(choice_of(&m), "held_out_samples")), want);
        ASSERT(cand_num(&m, 0, "held_out_samples") > 0);
        ASSERT(cand_num(&m, 0, "held_out_samples") <= want);
    }
    /* srbf is not tried from one view, and says why */
    ASSERT_EQ(json_array_size(json_object_get(choice_of(&m), "candidates")), 5);
    ASSERT(!strcmp(json_string_value(json_object_get(
                       json_array_get(json_object_get(choice_of(&m), "not_tried"), 0), "method")),
                   "srbf"));
    printf("  one view: chose %s, kd %.4f (held out: simplest %.6g, correction %.6g)\n",
           json_string_value(json_object_get(choice_of(&m), "chosen")),
           pbr_material_of(&m) ? pbr_material_of(&m)->kd[0] : -1.0,
           cand_num(&m, 0, "held_out_rms"), cand_num(&m, 4, "held_out_rms"));
    /* the start is the correction only where it holds out no worse */
    ASSERT(!strcmp(choice_str(&m, "started_from"),
                   cand_str(&m, cand_num(&m, 4, "held_out_rms") <= cand_num(&m, 0, "held_out_rms")
                                    ? 4 : 0, "label")));
    ASSERT(cand_num(&m, 0, "held_out_rms") >= 0.0);
    material_free(&m);
    prep_release(C, pp);

    /* two views: each held out in turn, the last first */
    one[9] = 1;
    ASSERT_OK(auto_fit(&truth, one, &m, &pp, &e));
    {
        const json_t *f = json_object_get(choice_of(&m), "held_out_folds");
        ASSERT_EQ(json_array_size(f), 2);
        ASSERT_EQ(json_array_size(json_array_get(f, 0)), 1);
        ASSERT_EQ(json_array_size(json_array_get(f, 1)), 1);
        ASSERT_EQ(json_integer_value(json_array_get(json_array_get(f, 0), 0)), 9);
        ASSERT_EQ(json_integer_value(json_array_get(json_array_get(f, 1), 0)), 4);
    }
    material_free(&m);
    prep_release(C, pp);

    ASSERT((pp = prep_method(&method_auto_env, &p, NULL)) != NULL);
    s = prep_samples(pp);
    v = calloc(3 * (size_t)s->n, sizeof *v);
    /* all black: every candidate black, the first kept */
    ASSERT_OK(prep_fit(pp, NULL, v, &m, &e));
    ASSERT_EQ(chosen_index(&m), 0);
    for (int c = 0; c < 4; c++)
        ASSERT_NEAR(cand_num(&m, c, "held_out_rms"), 0.0, 1e-9);
    material_free(&m);
    /* a single painted pixel (in a kept view) */
    for (int i = 0; i < s->n; i++)
        if (s->view[i] == 0) {
            v[3 * (size_t)i] = v[3 * (size_t)i + 1] = v[3 * (size_t)i + 2] = 0.5f;
            break;
        }
    ASSERT_OK(prep_fit(pp, NULL, v, &m, &e));
    for (int c = 0; c < 4; c++)
        ASSERT(isfinite(cand_num(&m, c, "held_out_rms")));
    material_free(&m);
    /* NaN, in a held-out view too: refused, named */
    for (int i = 0; i < s->n; i++)
        if (s->view[i] == 8) {
            v[3 * (size_t)i + 1] = NAN;
            break;
        }
    ASSERT_EQ(prep_fit(pp, NULL, v, &m, &e), GLINT_ENONFINITE);
    ASSERT(strstr(e.msg, "not finite") != NULL);
    printf("  NaN: %s\n", e.msg);
    free(v);
    material_free(&truth);
    prep_release(C, pp);
}

TEST_LIST {
    TEST_ENTRY(pbr_env_leaves_held_samples_out),
    TEST_ENTRY(srbf_leaves_held_samples_out),
    TEST_ENTRY(holdout_on_one_preparation_is_the_folds),
    TEST_ENTRY(auto_env_chooses_and_reports),
    TEST_ENTRY(two_lobes_take_the_two_lobe_candidate),
    TEST_ENTRY(one_view_starts_from_the_correction),
    TEST_ENTRY(extremes),
};

TEST_MAIN()
