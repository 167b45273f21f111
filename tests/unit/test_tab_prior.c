/* test_tab_prior.c: the tab_prior method (core/methods/tab/tab_prior.h,
 * method_tab_prior.h): tab's table continued along theta_d by a prior
 * learned from measured materials' fits.
 *
 * - A learning table against an independent evaluation of the same
 *   average (the pair built here from h, its tangent and its binormal
 *   rather than by turning a frame), and a Lambertian's table constant.
 * - Learning: a family of Lambertians differs by one direction in the log
 *   (one component holds it all); components are clamped to the samples;
 *   too few materials, an unknown name and bad exclude syntax refused.
 * - The continuation: a family of materials that share their shape along
 *   theta_d (a synthetic fits file written here), one member left out of
 *   the learning and painted on the sphere (lights 20 to 70 degrees from
 *   the eyes: theta_d 10 to 35 degrees); at theta_d 42 and 48 degrees its
 *   table comes back within a few percent with the prior and far off
 *   without it (tab's linear continuation), and the painted rows keep
 *   tab's fit; with a stricter threshold for painted nodes more is the
 *   prior's.
 * - The extremes: a black painting, a single painted pixel, NaN and
 *   infinity, one view only, no fits file (a message that says where they
 *   come from).
 * - On the shared measured set (skipped without it): learned on the 42
 *   materials a benchmark run with --every 4 does not judge, the rows
 *   beyond the painted range of red-phenolic and white-marble come closer
 *   to the truth's than tab's continuation does.
 *
 * The samples are those of the default scene (the sphere, 12 views) at 48 x
 * 48; values are f ci per unit light, computed at the samples. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "material.h"
#include "measured.h"
#include "method_tab_prior.h"
#include "raster.h"
#include "samples.h"
#include "scene.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

static scene SC;
static gbuf *G;
static samples S;     /* every view */
static samples S1;    /* view 0 alone */
static char FAMILY[256];

/* A fits file of eight materials sharing their shape along theta_d
 * (Fresnel, the 1 / (ci co) of sgd and a shadowing that sets in beyond
 * 0.6 radians, where a linear continuation from the painted rows misses
 * it), differing in diffuse, specular weight and roughness, with "held"
 * among them. */
static const char *family_doc(void)
{
    static char doc[16384];
    const double rd[8] = {0.05, 0.2, 0.4, 0.1, 0.3, 0.15, 0.25, 0.35};
    const double rs[8] = {0.2, 0.5, 0.1, 0.8, 0.3, 0.6, 0.4, 0.25};
    const double al[8] = {0.02, 0.05, 0.1, 0.03, 0.08, 0.04, 0.06, 0.07};
    size_t o = 0;
    o += (size_t)snprintf(doc + o, sizeof doc - o, "{\"materials\": [");
    for (int i = 0; i < 8; i++) {
        const char *name = i == 5 ? "held" : NULL;
        char nb[16];
        snprintf(nb, sizeof nb, "m%d", i);
        o += (size_t)snprintf(
            doc + o, sizeof doc - o,
            "%s{\"name\": \"%s\", \"abc\": {\"kD\": [%g, %g, %g], \"A\": [1, 1, 1], \"B\": 10, "
            "\"C\": 1, \"ior\": 1.5}, \"sgd\": {\"rhoD\": [%g, %g, %g], \"rhoS\": [%g, %g, %g], "
            "\"alpha\": [%g, %g, %g], \"p\": [0.5, 0.5, 0.5], \"f0\": [0.04, 0.04, 0.04], "
            "\"f1\": [0, 0, 0], \"kap\": [0.3, 0.3, 0.3], \"lambda\": [1, 1, 1], "
            "\"c\": [2, 2, 2], \"k\": [2, 2, 2], \"theta0\": [0.6, 0.6, 0.6]}}",
            i ? ", " : "", name ? name : nb, rd[i], rd[i], rd[i], rd[i], 0.8 * rd[i],
            0.6 * rd[i], rs[i], rs[i], rs[i], al[i], al[i], 1.2 * al[i]);
    }
    snprintf(doc + o, sizeof doc - o, "]}");
    return doc;
}

static void cleanup(void)
{
    unlink(FAMILY);
}

static int setup(void)
{
    scene_params sp;
    unsigned char one[SCENE_MAX_VIEWS] = {1};
    char h[33];
    glint_err e;
    FILE *f;
    if (S.n)
        return 0;
    scene_params_default(&sp);
    sp.width = sp.height = 48;
    if (scene_create(&sp, &SC, &e) || raster_scene(&SC, &G, &e) ||
        (scene_hash(&SC, h), samples_build(G, SC.views, SC.nviews, NULL, h, &S, &e)) ||
        samples_build(G, SC.views, SC.nviews, one, h, &S1, &e)) {
        fprintf(stderr, "setup: %s\n", e.msg);
        return -1;
    }
    snprintf(FAMILY, sizeof FAMILY, "/tmp/glint-test-tab-prior-%d.json", (int)getpid());
    if (!(f = fopen(FAMILY, "w")))
        return -1;
    fputs(family_doc(), f);
    fclose(f);
    atexit(cleanup);
    measured_set_file(FAMILY, NULL);
    return 0;
}

static int family_set(measured_set *s)
{
    glint_err e;
    const char *doc = family_doc();
    return measured_parse(doc, strlen(doc), "family.json", s, &e);
}

/* Values of a measured truth at the samples (malloc'ed, 3 n). */
static float *values_of(const measured_truth *mt, const samples *s)
{
    float *v = malloc(3 * sizeof(float) * (size_t)s->n);
    for (int i = 0; v && i < s->n; i++) {
        double n[3], wi[3], wo[3], f[3];
        for (int a = 0; a < 3; a++) {
            n[a] = s->nrm[3 * (size_t)i + a];
            wi[a] = s->wi[3 * (size_t)i + a];
            wo[a] = s->wo[3 * (size_t)i + a];
        }
        measured_eval(mt, n, wi, wo, f);
        for (int c = 0; c < 3; c++)
            v[3 * (size_t)i + c] = (float)(f[c] * s->cos_i[i]);
    }
    return v;
}

/* Fit values v on samples s with method m's parameters "name=value;...". */
static int fit_values(const method *m, const char *spec, const samples *s, const float *v,
                      material *out, glint_err *e)
{
    tab_prior_params tp;
    method_build_in bin;
    method_fit_in in;
    cache_value lv[3] = {{0}, {0}, {0}};
    const void *levels[3];
    const char *keys[3] = {"tab-design:test", "tab-operator:test", "tab-prior:test"};
    int rc = 0, built = 0;
    m->params_default(&tp);
    if (spec && spec[0]) {
        char buf[512], *tok, *save;
        snprintf(buf, sizeof buf, "%s", spec);
        for (tok = strtok_r(buf, ";", &save); tok; tok = strtok_r(NULL, ";", &save)) {
            char *eq = strchr(tok, '=');
            *eq = '\0';
            if ((rc = method_param_set_text(m, &tp, tok, eq + 1, e)))
                return rc;
        }
    }
    memset(&bin, 0, sizeof bin);
    bin.params = &tp;
    bin.s = s;
    bin.prev = levels;
    for (; built < m->nlevels && !rc; built++) {
        bin.level = built;
        if ((rc = m->levels[built].build(&bin, &lv[built], e)))
            break;
        levels[built] = lv[built].data;
    }
    if (!rc) {
        memset(&in, 0, sizeof in);
        in.params = &tp;
        in.s = s;
        in.rgb = v;
        in.levels = levels;
        in.keys = keys;
        rc = m->fit(&in, out, e);
    }
    while (built-- > 0)
        if (lv[built].free)
            lv[built].free(lv[built].data);
    return rc;
}

static json_t *info_at(const material *m, const char *a, const char *b)
{
    return json_object_get(json_object_get(m->info, a), b);
}

static int table_physical(const tab_material *tm)
{
    for (int k = 0; k < 3 * tab_nodes(&tm->g); k++)
        if (!isfinite(tm->t[k]) || tm->t[k] < 0.0)
            return 0;
    return 1;
}

/* ---- the learning tables ------------------------------------------------------------------ */

/* The average over phi_d of f at node (i, j), the pair built from h, a
 * tangent in the plane of n and h, and the binormal. */
static void node_direct(const tab_grid *g, const measured_truth *mt, int i, int j, double f[3])
{
    const double n[3] = {0, 0, 1}, top = 0.5 * M_PI - 1e-2;
    double th = fmin(tab_theta_h(g, i), top), td = fmin(tab_theta_d(g, j), top);
    double h[3] = {sin(th), 0, cos(th)}, t[3] = {cos(th), 0, -sin(th)}, b[3] = {0, 1, 0};
    int used = 0;
    f[0] = f[1] = f[2] = 0.0;
    for (int a = 0; a < PRIOR_PHI; a++) {
        double pd = M_PI * (a + 0.5) / PRIOR_PHI, wi[3], wo[3], x[3], hd = cos(td);
        for (int e = 0; e < 3; e++) {
            wi[e] = cos(td) * h[e] + sin(td) * (cos(pd) * t[e] + sin(pd) * b[e]);
            wo[e] = 2.0 * hd * h[e] - wi[e];
        }
        if (!(wi[2] > 1e-6 && wo[2] > 1e-6))
            continue;
        measured_eval(mt, n, wi, wo, x);
        for (int c = 0; c < 3; c++)
            f[c] += x[c];
        used++;
    }
    if (!used) {
        /* h near the horizon: the pair across it, phi_d = pi/2 */
        double wi[3], wo[3];
        for (int e = 0; e < 3; e++) {
            wi[e] = cos(td) * h[e] + sin(td) * b[e];
            wo[e] = 2.0 * cos(td) * h[e] - wi[e];
        }
        measured_eval(mt, n, wi, wo, f);
        used = 1;
    }
    for (int c = 0; c < 3; c++)
        f[c] /= used;
}

TEST(learning_table_against_a_direct_average)
{
    measured_set s;
    measured_truth mt;
    tab_grid g = {32, 16};
    double *t = malloc(3 * 512 * sizeof *t), f[3];
    ASSERT_OK(family_set(&s));
    measured_truth_of(measured_find(&s, "m1"), MEASURED_SGD, &mt);
    tab_prior_table(&g, &mt, t);
    for (int j = 0; j < 16; j++)
        for (int i = 0; i < 32; i++) {
            node_direct(&g, &mt, i, j, f);
            for (int c = 0; c < 3; c++)
                ASSERT_MSG(fabs(t[3 * (j * 32 + i) + c] - f[c]) <= 1e-9 * fmax(f[c], 1.0),
                           "node (%d, %d) channel %d: %.9g against %.9g", i, j, c,
                           t[3 * (j * 32 + i) + c], f[c]);
        }
    free(t);
    measured_free(&s);
}

TEST(lambertian_table_is_constant)
{
    measured_set s;
    measured_truth mt;
    tab_grid g = {16, 8};
    double t[3 * 128];
    ASSERT_OK(family_set(&s));
    measured_truth_of(measured_find(&s, "m2"), MEASURED_SGD, &mt);
    for (int c = 0; c < 3; c++)
        mt.sgd.rho_s[c] = 0.0;
    tab_prior_table(&g, &mt, t);
    for (int k = 0; k < 128; k++)
        for (int c = 0; c < 3; c++)
            ASSERT_NEAR(t[3 * k + c], mt.sgd.rho_d[c] / M_PI, 1e-12);
    measured_free(&s);
}

/* ---- learning ------------------------------------------------------------------------------- */

static int keep_lambertians(const void *cls, int i, const measured_material *m)
{
    (void)cls;
    (void)m;
    return i < 3;
}

TEST(lambertians_differ_by_one_direction)
{
    measured_set s;
    tab_grid g = {16, 8};
    tab_prior p;
    glint_err e;
    ASSERT_OK(family_set(&s));
    for (int i = 0; i < s.n; i++)
        for (int c = 0; c < 3; c++)
            s.m[i].sgd.rho_s[c] = 0.0;
    ASSERT_OK(tab_prior_learn(&g, &s, MEASURED_SGD, keep_lambertians, NULL, 1, &p, &e));
    ASSERT_EQ(p.materials, 3);
    ASSERT_EQ(p.k, 1);
    ASSERT_NEAR(p.explained, 1.0, 1e-9);
    /* the direction is constant over the covered nodes (theta_d <= 60: 5 of 8 rows) */
    ASSERT_EQ(p.nodes, 5 * 16);
    for (int a = 1; a < p.nodes; a++)
        ASSERT_NEAR(p.Q[a], p.Q[0], 1e-9 * fabs(p.Q[0]));
    tab_prior_free(&p);
    /* 64 components of 9 samples: 8 */
    ASSERT_OK(tab_prior_learn(&g, &s, MEASURED_SGD, keep_lambertians, NULL, 64, &p, &e));
    ASSERT_EQ(p.k, 8);
    tab_prior_free(&p);
    measured_free(&s);
}

static int keep_one(const void *cls, int i, const measured_material *m)
{
    (void)cls;
    (void)m;
    return i == 0;
}

TEST(learning_refuses_what_it_cannot_learn_from)
{
    measured_set s;
    tab_grid g = {16, 8};
    tab_prior p;
    glint_err e;
    tab_prior_params tp;
    ASSERT_OK(family_set(&s));
    ASSERT_EQ(tab_prior_learn(&g, &s, MEASURED_SGD, keep_one, NULL, 4, &p, &e), GLINT_EINVAL);
    ASSERT(strstr(e.msg, "at least 2") != NULL);
    ASSERT_EQ(tab_prior_learn(&g, &s, MEASURED_SGD, NULL, NULL, 0, &p, &e), GLINT_EINVAL);
    measured_free(&s);
    method_tab_prior.params_default(&tp);
    ASSERT_EQ(method_param_set_text(&method_tab_prior, &tp, "exclude", "every/0", &e),
              GLINT_EINVAL);
    ASSERT_EQ(method_param_set_text(&method_tab_prior, &tp, "exclude", "a++b", &e),
              GLINT_EINVAL);
    ASSERT_EQ(method_param_set_text(&method_tab_prior, &tp, "exclude", "Upper", &e),
              GLINT_EINVAL);
    ASSERT_EQ(method_param_set_text(&method_tab_prior, &tp, "exclude", "../x", &e),
              GLINT_EINVAL);
    ASSERT_EQ(method_param_set_text(&method_tab_prior, &tp, "noise", "0", &e), GLINT_EINVAL);
    ASSERT_OK(method_param_set_text(&method_tab_prior, &tp, "exclude", "m1+held", &e));
    ASSERT_OK(method_param_set_text(&method_tab_prior, &tp, "exclude", "every/4", &e));
}

/* ---- the continuation ---------------------------------------------------------------------- */

/* The relative RMS of a table against the truth's over rows j0..j1 and the
 * columns from theta_h 1.5 to 40 degrees (the highlight's side; the
 * columns nearer the peak are cells too narrow for the 48 x 48 sphere's
 * samples, which the continuation leaves as tab fills them). */
static double rows_error(const tab_material *tm, const measured_truth *mt, int j0, int j1)
{
    double se = 0.0, sr = 0.0, f[3];
    for (int j = j0; j <= j1; j++)
        for (int i = 0; i < tm->g.res_h; i++) {
            if (tab_theta_h(&tm->g, i) < 1.5 * M_PI / 180.0 ||
                tab_theta_h(&tm->g, i) > 40.0 * M_PI / 180.0)
                continue;
            node_direct(&tm->g, mt, i, j, f);
            for (int c = 0; c < 3; c++) {
                double d = tm->t[3 * (j * tm->g.res_h + i) + c] - f[c];
                se += d * d;
                sr += f[c] * f[c];
            }
        }
    return sqrt(se / sr);
}

TEST(grazing_rows_follow_the_family)
{
    measured_set s;
    measured_truth mt;
    material mp, mt0;
    glint_err e;
    float *v;
    const tab_material *tp, *tt;
    double ep, et;
    ASSERT_OK(setup());
    ASSERT_OK(family_set(&s));
    measured_truth_of(measured_find(&s, "held"), MEASURED_SGD, &mt);
    ASSERT((v = values_of(&mt, &S)) != NULL);
    ASSERT_OK(fit_values(&method_tab_prior, "exclude=held", &S, v, &mp, &e));
    ASSERT((tp = tab_material_of(&mp)) != NULL);
    ASSERT_EQ(json_integer_value(info_at(&mp, "prior", "learned_from")), 7);
    ASSERT(table_physical(tp));
    /* rows 9 and 10: theta_d 54 and 60 degrees, beyond every painted pair
     * (the sphere's lights reach theta_d 45) */
    ep = rows_error(tp, &mt, 9, 10);
    ASSERT_LT(ep, 0.05);
    /* tab's own continuation is far off there */
    ASSERT_OK(fit_values(&method_tab, "", &S, v, &mt0, &e));
    tt = tab_material_of(&mt0);
    et = rows_error(tt, &mt, 9, 10);
    ASSERT_LT(4.0 * ep, et);
    /* row 4 (theta_d 24 degrees) is painted: tab's fit, unchanged */
    for (int i = 0; i < 24; i++)
        for (int c = 0; c < 3; c++)
            ASSERT_EQ(tp->t[3 * (4 * 32 + i) + c] == tt->t[3 * (4 * 32 + i) + c], 1);
    material_free(&mt0);
    /* with painted = 1 only nodes weighed on as much as the median one
     * count: more of the painted rows are the prior's */
    ASSERT_OK(fit_values(&method_tab_prior, "exclude=held;painted=1", &S, v, &mt0, &e));
    ASSERT(json_number_value(json_array_get(info_at(&mt0, "prior", "changed"), 0)) >=
           json_number_value(json_array_get(info_at(&mp, "prior", "changed"), 0)));
    material_free(&mp);
    material_free(&mt0);
    free(v);
    measured_free(&s);
}

/* ---- the extremes -------------------------------------------------------------------------- */

TEST(black_painting)
{
    material m;
    glint_err e;
    float *v;
    const tab_material *tm;
    ASSERT_OK(setup());
    v = calloc(3 * (size_t)S.n, sizeof *v);
    ASSERT_OK(fit_values(&method_tab_prior, "exclude=held", &S, v, &m, &e));
    tm = tab_material_of(&m);
    ASSERT(table_physical(tm));
    /* the continuation of 0 along any shape is 0 */
    for (int k = 0; k < 3 * tab_nodes(&tm->g); k++)
        ASSERT_EQ(tm->t[k] == 0.0, 1);
    material_free(&m);
    free(v);
}

TEST(single_painted_pixel)
{
    samples one;
    material m;
    glint_err e;
    float v[3] = {0.1f, 0.2f, 0.05f};
    ASSERT_OK(setup());
    one = S;
    one.n = 1;
    ASSERT_OK(fit_values(&method_tab_prior, "exclude=held", &one, v, &m, &e));
    ASSERT(table_physical(tab_material_of(&m)));
    ASSERT_EQ(json_integer_value(info_at(&m, "prior", "observed")) <= 4, 1);
    material_free(&m);
}

TEST(nonfinite_painting_is_refused)
{
    material m;
    glint_err e;
    float *v;
    ASSERT_OK(setup());
    v = calloc(3 * (size_t)S.n, sizeof *v);
    v[3 * 100 + 1] = NAN;
    memset(&m, 0, sizeof m);
    ASSERT_EQ(fit_values(&method_tab_prior, "exclude=held", &S, v, &m, &e), GLINT_ENONFINITE);
    ASSERT(strstr(e.msg, "tab_prior") != NULL && strstr(e.msg, "100") != NULL);
    v[3 * 100 + 1] = 0.0f;
    v[5] = INFINITY;
    ASSERT_EQ(fit_values(&method_tab_prior, "exclude=held", &S, v, &m, &e), GLINT_ENONFINITE);
    ASSERT(m.method == NULL);
    free(v);
}

TEST(one_view_only)
{
    measured_set s;
    measured_truth mt;
    material m;
    glint_err e;
    float *v;
    ASSERT_OK(setup());
    ASSERT_OK(family_set(&s));
    measured_truth_of(measured_find(&s, "held"), MEASURED_SGD, &mt);
    ASSERT((v = values_of(&mt, &S1)) != NULL);
    ASSERT_OK(fit_values(&method_tab_prior, "exclude=held", &S1, v, &m, &e));
    ASSERT(table_physical(tab_material_of(&m)));
    ASSERT(json_integer_value(info_at(&m, "prior", "observed")) > 0);
    material_free(&m);
    free(v);
    measured_free(&s);
}

TEST(unknown_names_and_no_fits_file_are_refused)
{
    material m;
    glint_err e;
    float *v;
    ASSERT_OK(setup());
    v = calloc(3 * (size_t)S.n, sizeof *v);
    ASSERT_EQ(fit_values(&method_tab_prior, "exclude=nosuch", &S, v, &m, &e), GLINT_EINVAL);
    ASSERT(strstr(e.msg, "params.exclude: \"nosuch\" is not one of the") != NULL);
    ASSERT_OK(method_available(&method_tab_prior, &e));
    /* the same name refused before any work, as the API checks a fit */
    {
        void *p = method_params_new(&method_tab_prior);
        method_source src = {1};
        ASSERT(p != NULL);
        ASSERT_OK(method_param_set_text(&method_tab_prior, p, "exclude", "held+nosuch", &e));
        ASSERT_EQ(method_params_usable(&method_tab_prior, p, &src, &e), GLINT_EINVAL);
        ASSERT(strstr(e.msg, "params.exclude: \"nosuch\" is not one of the") != NULL);
        ASSERT_OK(method_param_set_text(&method_tab_prior, p, "exclude", "held", &e));
        ASSERT_OK(method_params_usable(&method_tab_prior, p, &src, &e));
        free(p);
    }
    measured_set_file(NULL, "$GLINT_MEASURED_DIR");
    ASSERT(fit_values(&method_tab_prior, "", &S, v, &m, &e) != 0);
    ASSERT(strstr(e.msg, "measured") != NULL);
    /* without fits the host cannot fit it at all, and says why */
    ASSERT_EQ(method_available(&method_tab_prior, &e), GLINT_ENOTFOUND);
    ASSERT(strstr(e.msg, "there are none: no measured fits here: $GLINT_MEASURED_DIR") != NULL);
    ASSERT_OK(method_available(&method_tab, &e)); /* a method without the hook: always */
    measured_set_file(FAMILY, NULL);
    ASSERT_OK(method_available(&method_tab_prior, &e));
    free(v);
}

/* ---- the shared measured set --------------------------------------------------------------- */

TEST(measured_plastics_beyond_the_painted_range)
{
    const char *data = check_data_dir(), *names[2] = {"red-phenolic", "white-marble"};
    char path[4200];
    measured_set s;
    glint_err e;
    ASSERT_OK(setup());
    if (!data) {
        printf("skipped: no shared data\n");
        return;
    }
    snprintf(path, sizeof path, "%s/measured/%s", data, MEASURED_FITS_FILE);
    if (access(path, R_OK) != 0) {
        printf("skipped: no %s\n", path);
        return;
    }
    ASSERT_OK(measured_load(path, &s, &e));
    measured_set_file(path, NULL);
    for (int a = 0; a < 2; a++) {
        measured_truth mt;
        material mp, mt0;
        float *v;
        double ep, et;
        const measured_material *mm = measured_find(&s, names[a]);
        ASSERT(mm != NULL);
        /* both are judged by --every 4: materials 32 and 52 */
        ASSERT_EQ((int)(mm - s.m) % 4, 0);
        measured_truth_of(mm, MEASURED_SGD, &mt);
        ASSERT((v = values_of(&mt, &S)) != NULL);
        ASSERT_OK(fit_values(&method_tab_prior, "exclude=every/4", &S, v, &mp, &e));
        ASSERT_OK(fit_values(&method_tab, "", &S, v, &mt0, &e));
        ASSERT_EQ(json_integer_value(info_at(&mp, "prior", "learned_from")), 42);
        ep = rows_error(tab_material_of(&mp), &mt, 8, 9);
        et = rows_error(tab_material_of(&mt0), &mt, 8, 9);
        printf("%s: theta_d 48 to 54 degrees: %.1f%% with the prior, %.1f%% without\n", names[a],
               100 * ep, 100 * et);
        ASSERT_LT(ep, 0.5 * et);
        material_free(&mp);
        material_free(&mt0);
        free(v);
    }
    measured_set_file(FAMILY, NULL);
    measured_free(&s);
}

TEST_LIST {
    TEST_ENTRY(learning_table_against_a_direct_average),
    TEST_ENTRY(lambertian_table_is_constant),
    TEST_ENTRY(lambertians_differ_by_one_direction),
    TEST_ENTRY(learning_refuses_what_it_cannot_learn_from),
    TEST_ENTRY(grazing_rows_follow_the_family),
    TEST_ENTRY(black_painting),
    TEST_ENTRY(single_painted_pixel),
    TEST_ENTRY(nonfinite_painting_is_refused),
    TEST_ENTRY(one_view_only),
    TEST_ENTRY(unknown_names_and_no_fits_file_are_refused),
    TEST_ENTRY(measured_plastics_beyond_the_painted_range),
};

TEST_MAIN()
