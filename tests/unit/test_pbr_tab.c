/* test_pbr_tab.c: the pbr_tab method (core/methods/pbr_tab): the pbr fit
 * with a table over half and difference angles of what it leaves.
 *
 *   - a truth of the pbr model itself leaves the table at its identity (0
 *     added, or 1 multiplied: within 1e-4) and the product's painted error
 *     at the base's;
 *   - truths the GGX family cannot represent (a Phong lobe; measured sgd
 *     fits from ../shared/data/measured when present): on a view left out
 *     of the painting the product's error is below 0.8 of the pbr fit's
 *     alone (measured: 7% to 68%);
 *   - where no painted sample reaches, the prior continues the table and
 *     the pull draws it to its identity: from one painted view (61 of 512
 *     nodes reached) the nodes at theta_d 90 degrees hold less than half
 *     the largest correction at a reached node (measured: 0.85 against
 *     4.26 at the default pull 1e-10; the continuation peaks at 8.9 in
 *     between, which a stronger pull, 1e-6, removes);
 *   - the levels are pbr's and tab's own cache entries;
 *   - the material saved and read back evaluates as the fitted one, and
 *     damaged manifests are refused with a message;
 *   - the GPU binding holds the table's texture and both parts' uniforms;
 *   - extremes: an all-black painting, a single painted sample, a painting
 *     brighter than physical (fitted, the base's clamp said), a Lambertian
 *     (the base's roughness undetermined, said; no correction), a mirror
 *     (the base's roughness at its floor, said), NaN and inf (refused,
 *     named), one view only.
 *
 * The scene is the default sphere (12 point-lit views) at 64 x 64; values
 * are f ci per unit light (scene.h), computed at the samples. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "method_pbr_tab.h"
#include "point_fixture.h"

#define HELD 5

/* f of a pbr material (its value over ci). */
static void pbr_truth(const void *cls, const double n[3], const double wi[3],
                      const double wo[3], double f[3])
{
    double ci = n[0] * wi[0] + n[1] * wi[1] + n[2] * wi[2];
    pbr_material_ops.eval(cls, NULL, n, wi, wo, f);
    for (int c = 0; c < 3; c++)
        f[c] = ci > 0.0 ? f[c] / ci : 0.0;
}

static double corr_num(const material *m, const char *key)
{
    return json_number_value(json_object_get(json_object_get(m->info, "correction"), key));
}

/* Fit a truth with method m (params) on the views in use (NULL: all). */
static int fit_truth(const method *m, const void *params, const unsigned char *use, truth_fn f,
                     const void *cls, material *out, glint_err *e)
{
    prep *pp;
    float *v;
    int rc;
    if (!(pp = prep_of(m, params, use)))
        return glint_err_set(e, GLINT_EINTERNAL, "no preparation");
    v = values_of(f, cls, prep_samples(pp));
    rc = v ? prep_fit(pp, NULL, v, out, e) : GLINT_ENOMEM;
    free(v);
    prep_release(C, pp);
    return rc;
}

/* The RMS error of material m on view `view` of the whole scene's samples
 * against a truth, per unit light. */
static double view_rms(const material *m, int view, truth_fn f, const void *cls)
{
    pbr_tab_params p;
    prep *pp;
    const samples *s;
    double ss = 0.0;
    long cnt = 0;
    method_pbr_tab.params_default(&p);
    if (!(pp = prep_of(&method_pbr_tab, &p, NULL)))
        return NAN;
    s = prep_samples(pp);
    for (int i = 0; i < s->n; i++) {
        double n[3], wi[3], wo[3], x[3], y[3];
        if (s->view[i] != view)
            continue;
        dirs_of(s, i, n, wi, wo);
        material_eval(m, n, wi, wo, x);
        f(cls, n, wi, wo, y);
        for (int c = 0; c < 3; c++) {
            double d = x[c] - y[c] * s->cos_i[i];
            ss += d * d;
        }
        cnt++;
    }
    prep_release(C, pp);
    return cnt ? sqrt(ss / (3.0 * cnt)) : NAN;
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

static void ggx_truth_for(int combine)
{
    pbr_material truth;
    pbr_tab_params p;
    material m = {0};
    glint_err e;
    const pbr_tab_material *x;
    double id = combine == PBR_TAB_MULTIPLY ? 1.0 : 0.0, worst = 0.0;
    int nodes;

    method_pbr_tab.params_default(&p);
    p.combine = combine;
    known_base(&truth);
    ASSERT_OK(fit_truth(&method_pbr_tab, &p, NULL, pbr_truth, &truth, &m, &e));
    ASSERT((x = pbr_tab_material_of(&m)) != NULL);
    ASSERT_EQ(x->combine, combine);
    nodes = tab_nodes(&x->table.g);
    for (int k = 0; k < 3 * nodes; k++)
        worst = fmax(worst, fabs(x->table.t[k] - id));
    printf("  %s: base rms %.3g, product rms %.3g, largest |table - %g| %.3g\n",
           combine == PBR_TAB_MULTIPLY ? "multiply" : "add", corr_num(&m, "rms_painted_base"),
           corr_num(&m, "rms_painted"), id, worst);
    ASSERT_LE(corr_num(&m, "rms_painted"), corr_num(&m, "rms_painted_base") + 1e-6);
    ASSERT_LT(worst, 1e-4);
    material_free(&m);
}

TEST(ggx_truth_leaves_the_table_at_its_identity)
{
    ASSERT(setup() == 0);
    ggx_truth_for(PBR_TAB_ADD);
    ggx_truth_for(PBR_TAB_MULTIPLY);
}

TEST(levels_are_pbr_and_tab_entries)
{
    pbr_tab_params p;
    prep *pp, *q = NULL;
    glint_err e;
    unsigned char all[SCENE_MAX_VIEWS] = {0};
    prep_request rq = {NULL, NULL, NULL, all, NULL};

    ASSERT(setup() == 0);
    method_pbr_tab.params_default(&p);
    ASSERT((pp = prep_of(&method_pbr_tab, &p, NULL)) != NULL);
    for (int v = 0; v < SC.nviews; v++)
        all[v] = 1;
    rq.scene = SE;
    rq.m = &method_pbr;
    rq.params = &p.pbr;
    ASSERT_OK(prep_try(C, &rq, &q, &e));
    prep_release(C, q);
    /* tab's design is there; its operator (a level pbr_tab does not use) is not */
    rq.m = &method_tab;
    rq.params = &p.tab;
    ASSERT(prep_try(C, &rq, &q, &e) == GLINT_ENOTFOUND);
    p.tab.res_h = 20;
    rq.params = &p.tab;
    ASSERT(prep_try(C, &rq, &q, &e) == GLINT_ENOTFOUND);
    prep_release(C, pp);
}

/* On view HELD, left out of the painting: the product against pbr alone. */
static void check_new_view(truth_fn f, const void *cls, const char *what)
{
    unsigned char most[SCENE_MAX_VIEWS] = {0};
    pbr_tab_params p;
    material m = {0}, b = {0};
    glint_err e;
    double rp, rb;
    for (int v = 0; v < SC.nviews; v++)
        most[v] = v != HELD;
    method_pbr_tab.params_default(&p);
    ASSERT_MSG(fit_truth(&method_pbr_tab, &p, most, f, cls, &m, &e) == 0, "%s: %s", what,
               e.msg);
    ASSERT_MSG(fit_truth(&method_pbr, &p.pbr, most, f, cls, &b, &e) == 0, "%s: %s", what,
               e.msg);
    rp = view_rms(&m, HELD, f, cls);
    rb = view_rms(&b, HELD, f, cls);
    printf("  %s, view %d unpainted: pbr %.4g, pbr_tab %.4g (%.0f%%)\n", what, HELD, rb, rp,
           100.0 * rp / rb);
    ASSERT_FINITE(rp);
    ASSERT_LT(rp, 0.8 * rb);
    material_free(&m);
    material_free(&b);
}

TEST(new_view_gains_over_the_base)
{
    brdf b;
    glint_err e;
    ASSERT(setup() == 0);
    ASSERT_OK(brdf_parse("phong:kd=0.4/0.3/0.2,ks=0.4,e=32", &b, &e));
    check_new_view(brdf_truth, &b, "phong e 32");
}

TEST(measured_truths_gain_on_a_new_view)
{
    ASSERT(setup() == 0);
    each_measured(check_new_view);
}

TEST(pull_returns_unreached_nodes_to_the_base)
{
    unsigned char one[SCENE_MAX_VIEWS] = {1};
    pbr_tab_params p;
    brdf b;
    material m = {0};
    glint_err e;
    const pbr_tab_material *x;
    const samples *s;
    prep *pp;
    tab_design d;
    double far = 0.0, reached = 0.0, all = 0.0;
    int rh, rd;

    ASSERT(setup() == 0);
    ASSERT_OK(brdf_parse("phong:kd=0.4/0.3/0.2,ks=0.4,e=32", &b, &e));
    method_pbr_tab.params_default(&p);
    ASSERT_OK(fit_truth(&method_pbr_tab, &p, one, brdf_truth, &b, &m, &e));
    ASSERT((x = pbr_tab_material_of(&m)) != NULL);
    rh = x->table.g.res_h;
    rd = x->table.g.res_d;
    /* one view's light is 20 degrees from its eye: theta_d about 10 degrees
     * everywhere; the last row (theta_d 90 degrees) is far from every sample */
    ASSERT((pp = prep_of(&method_pbr_tab, &p, one)) != NULL);
    s = prep_samples(pp);
    ASSERT_OK(tab_design_build(&x->table.g, s, &d, &e));
    ASSERT_LT(d.reached, rh * rd / 2);
    for (int k = 0; k < rh * rd; k++)
        for (int c = 0; c < 3; c++) {
            double t = fabs(x->table.t[3 * (size_t)k + c]);
            all = fmax(all, t);
            if (d.gram[(size_t)k * rh * rd + k] > 0.0)
                reached = fmax(reached, t);
        }
    for (int i = 0; i < rh; i++)
        for (int c = 0; c < 3; c++)
            far = fmax(far, fabs(x->table.t[3 * (size_t)((rd - 1) * rh + i) + c]));
    printf("  one view (%d nodes reached): largest correction %.4g at a reached node, %.4g "
           "anywhere, %.4g at theta_d 90 degrees\n",
           d.reached, reached, all, far);
    ASSERT(reached > 0.0);
    ASSERT_LT(far, 0.5 * reached);
    tab_design_free(&d);
    prep_release(C, pp);
    material_free(&m);
}

/* Rewrite dir/material.json: member `key` of `part` (NULL part: the root)
 * replaced by `value` (JSON text; NULL: removed). */
static int damage(const char *dir, const char *part, const char *key, const char *value)
{
    char path[256];
    json_t *root, *o;
    int rc;
    snprintf(path, sizeof path, "%s/material.json", dir);
    if (!(root = json_load_file(path, 0, NULL)))
        return -1;
    o = part ? json_object_get(root, part) : root;
    if (o && !value)
        json_object_del(o, key);
    else if (o)
        json_object_set_new(o, key, json_loads(value, JSON_DECODE_ANY, NULL));
    rc = json_dump_file(root, path, 0);
    json_decref(root);
    return rc;
}

TEST(material_files_round_trip_and_damage)
{
    brdf b;
    pbr_tab_params p;
    material m = {0}, r = {0};
    glint_err e;
    char dir[] = "/tmp/glint-pbr-tab-XXXXXX", path[256];
    double d;
    json_t *sum;

    ASSERT(setup() == 0);
    ASSERT_OK(brdf_parse("phong:kd=0.4/0.3/0.2,ks=0.4,e=32", &b, &e));
    method_pbr_tab.params_default(&p);
    ASSERT_OK(fit_truth(&method_pbr_tab, &p, NULL, brdf_truth, &b, &m, &e));
    ASSERT(mkdtemp(dir) != NULL);
    ASSERT_OK(material_save(&m, dir, &e));
    ASSERT_OK(material_load(dir, &r, &e));
    ASSERT(pbr_tab_material_of(&r) != NULL);
    d = materials_diff(&r, &m);
    printf("  read back: largest relative difference %.3g\n", d);
    ASSERT_LT(d, 1e-12);
    ASSERT((sum = material_summary(&r)) != NULL);
    ASSERT(json_is_string(json_object_get(sum, "fresnel")));
    ASSERT(json_is_array(json_object_get(sum, "diffuse")));
    ASSERT(json_is_string(json_object_get(sum, "detail")));
    json_decref(sum);
    material_free(&r);
    /* damaged parts are refused by their own method's checks, named */
    ASSERT(damage(dir, "base", "fresnel", "\"glass\"") == 0);
    ASSERT(material_load(dir, &r, &e) == GLINT_EFORMAT);
    ASSERT_MSG(strstr(e.msg, "base") && strstr(e.msg, "fresnel"), "%s", e.msg);
    ASSERT_OK(material_save(&m, dir, &e));
    ASSERT(damage(dir, "table", "res_h", "1") == 0);
    ASSERT(material_load(dir, &r, &e) == GLINT_EFORMAT);
    ASSERT_MSG(strstr(e.msg, "table") && strstr(e.msg, "res_h"), "%s", e.msg);
    ASSERT_OK(material_save(&m, dir, &e));
    ASSERT(damage(dir, NULL, "combine", "\"sideways\"") == 0);
    ASSERT(material_load(dir, &r, &e) == GLINT_EFORMAT);
    ASSERT_MSG(strstr(e.msg, "combine"), "%s", e.msg);
    ASSERT(damage(dir, NULL, "table", NULL) == 0);
    ASSERT(material_load(dir, &r, &e) == GLINT_EFORMAT);
    snprintf(path, sizeof path, "%s/material.json", dir);
    unlink(path);
    rmdir(dir);
    material_free(&m);
}

TEST(gpu_binding_holds_both_parts)
{
    pbr_material truth;
    pbr_tab_params p;
    material m = {0};
    material_gpu g;
    glint_err e;
    ASSERT(setup() == 0);
    known_base(&truth);
    method_pbr_tab.params_default(&p);
    ASSERT_OK(fit_truth(&method_pbr_tab, &p, NULL, pbr_truth, &truth, &m, &e));
    ASSERT_OK(material_gpu_get(&m, &g, &e));
    ASSERT(g.frag_src && strstr(g.frag_src, "glint_material") && g.tex);
    ASSERT_EQ(g.tex_w, p.tab.res_h);
    ASSERT_EQ(g.tex_h, p.tab.res_d);
    ASSERT_EQ(g.nuniforms, 10);
    for (int i = 0; i < g.nuniforms; i++)
        ASSERT_MSG(strstr(g.frag_src, g.uniform[i].name), "%s not in the shader",
                   g.uniform[i].name);
    ASSERT(json_is_object(json_object_get(g.manifest, "base")));
    ASSERT(json_is_object(json_object_get(g.manifest, "table")));
    material_gpu_free(&g);
    material_free(&m);
}

TEST(extremes)
{
    pbr_tab_params p;
    prep *pp;
    const samples *s;
    float *v;
    material m = {0};
    glint_err e;
    char *notes;

    ASSERT(setup() == 0);
    method_pbr_tab.params_default(&p);
    ASSERT((pp = prep_of(&method_pbr_tab, &p, NULL)) != NULL);
    s = prep_samples(pp);
    ASSERT((v = calloc(3 * (size_t)s->n, sizeof *v)) != NULL);
    /* all black: a black material */
    ASSERT_OK(prep_fit(pp, NULL, v, &m, &e));
    ASSERT(eval_finite(&m));
    ASSERT_LE(corr_num(&m, "rms_painted"), 1e-12);
    material_free(&m);
    /* a single painted sample: a finite material no worse than black */
    v[3 * (s->n / 2)] = v[3 * (s->n / 2) + 1] = v[3 * (s->n / 2) + 2] = 0.5f;
    ASSERT_OK(prep_fit(pp, NULL, v, &m, &e));
    ASSERT(eval_finite(&m));
    ASSERT_LE(corr_num(&m, "rms_painted"), values_rms(v, s->n));
    material_free(&m);
    /* brighter than any physical material (a Lambertian of albedo 1.6): the
     * base's diffuse held at 1 and said so; the table keeps the painting */
    for (int i = 0; i < s->n; i++)
        for (int c = 0; c < 3; c++)
            v[3 * (size_t)i + c] = (float)(1.6 / M_PI * s->cos_i[i]);
    ASSERT_OK(prep_fit(pp, NULL, v, &m, &e));
    notes = json_dumps(json_object_get(json_object_get(m.info, "base"), "notes"), 0);
    printf("  brighter than physical: base rms %.4g, product rms %.4g; base notes %s\n",
           corr_num(&m, "rms_painted_base"), corr_num(&m, "rms_painted"), notes);
    ASSERT(notes && strstr(notes, "clamped"));
    ASSERT_LT(corr_num(&m, "rms_painted"), 0.1 * corr_num(&m, "rms_painted_base"));
    free(notes);
    material_free(&m);
    /* NaN and inf: refused, the sample named */
    v[3 * 7 + 1] = NAN;
    ASSERT(prep_fit(pp, NULL, v, &m, &e) == GLINT_ENONFINITE);
    ASSERT_MSG(strstr(e.msg, "pbr_tab") && strstr(e.msg, "sample 7"), "%s", e.msg);
    v[3 * 7 + 1] = INFINITY;
    ASSERT(prep_fit(pp, NULL, v, &m, &e) == GLINT_ENONFINITE);
    ASSERT(m.method == NULL);
    free(v);
    prep_release(C, pp);
}

TEST(one_view_only)
{
    pbr_tab_params p;
    unsigned char one[SCENE_MAX_VIEWS] = {1};
    brdf b;
    material m = {0};
    glint_err e;
    const json_t *byv;

    ASSERT(setup() == 0);
    method_pbr_tab.params_default(&p);
    ASSERT_OK(brdf_parse("phong:kd=0.4/0.3/0.2,ks=0.4,e=32", &b, &e));
    ASSERT_OK(fit_truth(&method_pbr_tab, &p, one, brdf_truth, &b, &m, &e));
    ASSERT(eval_finite(&m));
    byv = json_object_get(json_object_get(m.info, "errors"), "rms_by_view");
    ASSERT_EQ(json_array_size(byv), 1);
    printf("  one view: base rms %.4g, product rms %.4g\n", corr_num(&m, "rms_painted_base"),
           corr_num(&m, "rms_painted"));
    ASSERT_LE(corr_num(&m, "rms_painted"), corr_num(&m, "rms_painted_base"));
    material_free(&m);
}

/* Whether JSON array a holds a string containing word. */
static int lists(const json_t *a, const char *word)
{
    for (size_t k = 0; k < json_array_size(a); k++) {
        const json_t *v = json_array_get(a, k);
        const char *t = json_is_string(v) ? json_string_value(v)
                                          : json_string_value(json_object_get(v, "name"));
        if (t && strstr(t, word))
            return 1;
    }
    return 0;
}

TEST(lambertian_and_mirror)
{
    pbr_tab_params p;
    pbr_material mirror;
    brdf b;
    material m = {0};
    glint_err e;
    const json_t *base;
    const pbr_tab_material *x;
    double worst = 0.0;

    ASSERT(setup() == 0);
    method_pbr_tab.params_default(&p);
    /* a Lambertian: the base's roughness is undetermined, said so, and the
     * table has nothing to add */
    ASSERT_OK(brdf_parse("lambert:kd=0.6/0.4/0.2", &b, &e));
    ASSERT_OK(fit_truth(&method_pbr_tab, &p, NULL, brdf_truth, &b, &m, &e));
    base = json_object_get(m.info, "base");
    ASSERT(lists(json_object_get(base, "undetermined"), "alpha"));
    x = pbr_tab_material_of(&m);
    for (int c = 0; c < 3; c++)
        ASSERT_NEAR(x->base.kd[c], 0.6 - 0.2 * c, 0.01 * (0.6 - 0.2 * c));
    for (int k = 0; k < 3 * tab_nodes(&x->table.g); k++)
        worst = fmax(worst, fabs(x->table.t[k]));
    printf("  lambertian: largest correction %.3g (f is %.3g..%.3g)\n", worst, 0.2 / M_PI,
           0.6 / M_PI);
    ASSERT_LT(worst, 1e-4);
    material_free(&m);
    /* a mirror-like highlight, sharper than the roughness's floor: the base's
     * roughness at its lower bound, said so */
    known_base(&mirror);
    mirror.p[3] = 0.0005;
    pbr_material_sync(&mirror);
    ASSERT_OK(fit_truth(&method_pbr_tab, &p, NULL, pbr_truth, &mirror, &m, &e));
    base = json_object_get(m.info, "base");
    x = pbr_tab_material_of(&m);
    printf("  mirror: base alpha %.4g (floor %.4g); base rms %.4g, product rms %.4g\n",
           x->base.lobe[0].alpha, PBR_ALPHA_MIN, corr_num(&m, "rms_painted_base"),
           corr_num(&m, "rms_painted"));
    ASSERT_NEAR(x->base.lobe[0].alpha, PBR_ALPHA_MIN, 1e-9);
    ASSERT(lists(json_object_get(base, "at_bound"), "alpha"));
    ASSERT(eval_finite(&m));
    ASSERT_LE(corr_num(&m, "rms_painted"), corr_num(&m, "rms_painted_base") + 1e-9);
    material_free(&m);
}

TEST(bad_parameters_are_refused)
{
    pbr_tab_params p;
    glint_err e;
    method_pbr_tab.params_default(&p);
    ASSERT(method_param_set_text(&method_pbr_tab, &p, "combine", "divide", &e) == GLINT_EINVAL);
    ASSERT(method_param_set_text(&method_pbr_tab, &p, "pull", "-1", &e) == GLINT_EINVAL);
    ASSERT(method_param_set_text(&method_pbr_tab, &p, "res_h", "91", &e) == GLINT_EINVAL);
    ASSERT_OK(method_param_set_text(&method_pbr_tab, &p, "res_h", "90", &e));
    ASSERT_OK(method_param_set_text(&method_pbr_tab, &p, "res_d", "64", &e));
    ASSERT(method_pbr_tab.params_check(&p, &e) == GLINT_EINVAL);
    ASSERT_MSG(strstr(e.msg, "nodes"), "%s", e.msg);
}

TEST_LIST {
    TEST_ENTRY(ggx_truth_leaves_the_table_at_its_identity),
    TEST_ENTRY(levels_are_pbr_and_tab_entries),
    TEST_ENTRY(new_view_gains_over_the_base),
    TEST_ENTRY(measured_truths_gain_on_a_new_view),
    TEST_ENTRY(pull_returns_unreached_nodes_to_the_base),
    TEST_ENTRY(material_files_round_trip_and_damage),
    TEST_ENTRY(gpu_binding_holds_both_parts),
    TEST_ENTRY(extremes),
    TEST_ENTRY(one_view_only),
    TEST_ENTRY(lambertian_and_mirror),
    TEST_ENTRY(bad_parameters_are_refused),
};

TEST_MAIN()
