/* Numerical extremes as a property of every method: each built-in method is
 * fitted
 *   - with each of its parameters in turn at the ends of its range (INT and
 *     NUMBER: the minimum, 0 included where allowed, and the maximum, capped
 *     where the precomputation would take minutes: see `cap`), at every
 *     value of an ENUM and every documented example of a TEXT parameter,
 *     the others at small values (method_small.h);
 *   - on extreme paintings at its small parameters: all black, one painted
 *     pixel, HDR (the painting times 1e3), a near-mirror highlight
 *     (Cook-Torrance, roughness 0.01), and one NaN pixel;
 * and each fit must end in a material whose evaluation is finite at every
 * direction pair of a grid, or in an error with a message (never a crash,
 * never GLINT_EINTERNAL); the NaN painting must be refused.  Prints each
 * case's time and relative error over the painted samples (the material's
 * own errors.rms_painted against the painting's RMS), and the slowest and
 * least accurate corners. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "clock.h"
#include "fsio.h"
#include "material.h"
#include "method_small.h"
#include "sv_fixture.h"

static scene sc;
static gbuf *gb;
static cache *cc;
static cache_entry *se;

typedef struct outcome {
    char what[160];
    double seconds, rel;    /* rel < 0: not reported by the material */
    int ok;
} outcome;

static outcome outs[1024];
static int nouts;

/* Finite everywhere on a grid of direction pairs (and two uvs)? */
static int material_finite(const material *m)
{
    for (int a = 0; a < 6; a++)
        for (int b = 0; b < 6; b++)
            for (int c = 0; c < 4; c++) {
                double ti = 1.5 * a / 5.0, to = 1.5 * b / 5.0, ph = 1.7 * c;
                double n[3] = {0, 0, 1}, wi[3] = {sin(ti), 0, cos(ti)},
                       wo[3] = {sin(to) * cos(ph), sin(to) * sin(ph), cos(to)}, rgb[3];
                double uv[2] = {0.3 + 0.1 * c, 0.7 - 0.1 * a};
                material_eval_at(m, uv, n, wi, wo, rgb);
                if (!isfinite(rgb[0]) || !isfinite(rgb[1]) || !isfinite(rgb[2]))
                    return 0;
            }
    return 1;
}

static double painting_rms(const img *im, int nviews)
{
    double ss = 0;
    long n = 0;
    for (int v = 0; v < nviews; v++)
        for (long i = 0; i < (long)im[v].width * im[v].height * im[v].channels; i++)
            if (im[v].px[i] != 0 && isfinite(im[v].px[i])) {
                ss += (double)im[v].px[i] * im[v].px[i];
                n++;
            }
    return n ? sqrt(ss / n) : 0;
}

/* errors.rms_painted of a material's info, or -1. */
static double rms_painted(const material *m)
{
    json_t *e = json_object_get(m->info, "errors"), *r = json_object_get(e, "rms_painted");
    return json_is_number(r) ? json_number_value(r) : -1;
}

/* Fit and judge one case; returns 0 when the property holds. */
static int run_case(const method *meth, const void *params, const img *im, const char *what,
                    int must_fail)
{
    unsigned char all[SCENE_MAX_VIEWS];
    prep_request rq = {meth, params, se, all, NULL};
    prep *pp = NULL;
    material m;
    glint_err e;
    outcome *o = &outs[nouts < 1024 ? nouts++ : 1023];
    double t0 = glint_now();
    int rc, good;
    memset(all, 1, sizeof all);
    memset(&e, 0, sizeof e);
    rc = prep_acquire(cc, &rq, NULL, NULL, &pp, &e);
    if (!rc)
        rc = prep_fit(pp, im, NULL, &m, &e);
    prep_release(cc, pp);
    snprintf(o->what, sizeof o->what, "%s %s", meth->name, what);
    o->seconds = glint_now() - t0;
    o->rel = -1;
    if (rc == 0) {
        double pr = painting_rms(im, sc.nviews), r = rms_painted(&m);
        good = !must_fail && m.method && material_finite(&m);
        if (r >= 0 && pr > 0)
            o->rel = r / pr;
        if (!good)
            fprintf(stderr, "  %s: %s\n", o->what,
                    must_fail ? "accepted a painting it must refuse" : "material not finite");
        material_free(&m);
    } else {
        good = e.msg[0] != '\0' && rc != GLINT_EINTERNAL;
        if (!good)
            fprintf(stderr, "  %s: error %d without a message: '%s'\n", o->what, rc, e.msg);
        if (must_fail && good)
            printf("  %-44s refused: %.100s\n", o->what, e.msg);
    }
    o->ok = good;
    return good ? 0 : 1;
}

/* The value to try at a parameter's upper end: the maximum, capped where the
 * precomputation grows too fast to sweep (cubes of s_res^2, res^3, ...; srbf's
 * energy rows with the lobes: 48 take 10 s, the default 147 30 s). */
static double cap(const method_param *p)
{
    static const struct { const char *name; double at; } caps[] = {
        {"res", 48}, {"s_res", 12}, {"res_2d", 12}, {"map_res", 64}, {"lights", 64},
        {"basis_res", 4}, {"components", 4}, {"refine", 20}, {"rounds", 8}, {"every", 8}};
    for (size_t i = 0; i < sizeof caps / sizeof *caps; i++)
        if (!strcmp(p->name, caps[i].name) && p->max > caps[i].at)
            return caps[i].at;
    return p->max;
}

static int sweep_params(const method *meth, const char *small, const img *im)
{
    int bad = 0;
    for (int k = 0; k < meth->nparams; k++) {
        const method_param *p = &meth->params[k];
        char vals[16][64];
        int nv = 0;
        if (p->type == METHOD_PARAM_INT || p->type == METHOD_PARAM_NUMBER) {
            double lo = p->min_exclusive ? nextafter(p->min, p->max) : p->min;
            double hi = p->max_exclusive ? nextafter(p->max, p->min) : cap(p);
            if (p->type == METHOD_PARAM_INT) {
                snprintf(vals[nv++], 64, "%d", (int)ceil(lo));
                snprintf(vals[nv++], 64, "%d", (int)floor(hi));
            } else {
                snprintf(vals[nv++], 64, "%.17g", lo);
                snprintf(vals[nv++], 64, "%.17g", hi);
            }
        } else if (p->type == METHOD_PARAM_ENUM) {
            for (int i = 0; p->values[i] && nv < 16; i++)
                snprintf(vals[nv++], 64, "%s", p->values[i]);
        } else {
            for (int i = 0; p->examples && p->examples[i] && nv < 16; i++)
                snprintf(vals[nv++], 64, "%s", p->examples[i]);
        }
        for (int i = 0; i < nv; i++) {
            void *params = method_params_new(meth);
            glint_err e;
            char what[128];
            snprintf(what, sizeof what, "%s=%s", p->name, vals[i]);
            if (method_small_set(meth, params, small, &e) ||
                method_param_set_text(meth, params, p->name, vals[i], &e)) {
                /* a value the cross checks refuse with the small ones is
                 * refused with a message: that is the property */
                outcome *o = &outs[nouts < 1024 ? nouts++ : 1023];
                snprintf(o->what, sizeof o->what, "%s %s", meth->name, what);
                o->ok = e.msg[0] != '\0';
                o->rel = -1;
                o->seconds = 0;
                bad += !o->ok;
                printf("  %-44s refused: %.100s\n", o->what, e.msg);
            } else {
                bad += run_case(meth, params, im, what, 0);
            }
            free(params);
        }
    }
    return bad;
}

static img paint_ct[SCENE_MAX_VIEWS], paint_x[SCENE_MAX_VIEWS];

static void copy_paint(const img *src, img *dst, double scale)
{
    for (int v = 0; v < sc.nviews; v++) {
        size_t n = (size_t)src[v].width * src[v].height * src[v].channels;
        img_free(&dst[v]);
        img_alloc(&dst[v], src[v].width, src[v].height, src[v].channels, NULL);
        for (size_t i = 0; i < n; i++)
            dst[v].px[i] = (float)(src[v].px[i] * scale);
    }
}

static int setup(void)
{
    static int done;
    glint_err e;
    if (done++)
        return 0;
    if (method_small_measured() || sv_setup(16, &sc, &gb, &cc, &se))
        return -1;
    if (sv_paint("ct:rough=0.3,kd=0.5,f0=0.3", &sc, gb, paint_ct, &e)) {
        fprintf(stderr, "painting: %s\n", e.msg);
        return -1;
    }
    return 0;
}

TEST(every_parameter_at_its_ends)
{
    int bad = 0;
    ASSERT_OK(setup());
    for (int i = 0; i < METHOD_SMALL_N; i++) {
        const method *meth = method_find(method_small[i][0]);
        ASSERT(meth);
        bad += sweep_params(meth, method_small[i][1], paint_ct);
    }
    ASSERT_EQ(bad, 0);
}

static int by_time(const void *a, const void *b)
{
    double x = ((const outcome *)a)->seconds, y = ((const outcome *)b)->seconds;
    return (x < y) - (x > y);
}

static int by_rel(const void *a, const void *b)
{
    double x = ((const outcome *)a)->rel, y = ((const outcome *)b)->rel;
    return (x < y) - (x > y);
}

/* The slowest and least accurate cases run so far. */
static void report_corners(void)
{
    static outcome sorted[1024];
    int n = nouts;
    memcpy(sorted, outs, (size_t)n * sizeof *outs);
    qsort(sorted, (size_t)n, sizeof *sorted, by_time);
    printf("  %d cases; the slowest:\n", n);
    for (int i = 0; i < 6 && i < n; i++)
        printf("    %8.3f s  %s\n", sorted[i].seconds, sorted[i].what);
    qsort(sorted, (size_t)n, sizeof *sorted, by_rel);
    printf("  the least accurate on the painted samples (rms_painted / painting RMS):\n");
    for (int i = 0; i < 6 && i < n && sorted[i].rel >= 0; i++)
        printf("    %8.4f    %s\n", sorted[i].rel, sorted[i].what);
}

TEST(extreme_paintings)
{
    int bad = 0;
    ASSERT_OK(setup());
    for (int i = 0; i < METHOD_SMALL_N; i++) {
        const method *meth = method_find(method_small[i][0]);
        void *params = method_params_new(meth);
        glint_err e;
        ASSERT(meth && params);
        ASSERT_OK(method_small_set(meth, params, method_small[i][1], &e));
        /* all black */
        copy_paint(paint_ct, paint_x, 0.0);
        bad += run_case(meth, params, paint_x, "painting all black", 0);
        /* one painted pixel: the brightest of view 0 */
        {
            size_t best = 0, n = (size_t)paint_ct[0].width * paint_ct[0].height;
            for (size_t p = 0; p < n; p++)
                if (paint_ct[0].px[3 * p] > paint_ct[0].px[3 * best])
                    best = p;
            for (int c = 0; c < 3; c++)
                paint_x[0].px[3 * best + c] = paint_ct[0].px[3 * best + c];
            bad += run_case(meth, params, paint_x, "one painted pixel", 0);
        }
        copy_paint(paint_ct, paint_x, 1e3);
        bad += run_case(meth, params, paint_x, "HDR painting (x 1e3)", 0);
        {
            img mirror[SCENE_MAX_VIEWS];
            ASSERT_OK(sv_paint("ct:rough=0.01,kd=0.1,f0=0.9", &sc, gb, mirror, &e));
            bad += run_case(meth, params, mirror, "near-mirror highlight (ct rough 0.01)", 0);
            for (int v = 0; v < sc.nviews; v++)
                img_free(&mirror[v]);
        }
        copy_paint(paint_ct, paint_x, 1.0);
        {
            size_t n = (size_t)paint_x[3].width * paint_x[3].height, p = n / 2;
            while (p < n && paint_x[3].px[3 * p] == 0)
                p++;
            paint_x[3].px[3 * (p < n ? p : n / 2) + 1] = NAN;
        }
        bad += run_case(meth, params, paint_x, "one NaN pixel", 1);
        free(params);
    }
    report_corners();
    ASSERT_EQ(bad, 0);
}

/* The bytes of dir/name (OUT: *len), NULL when unreadable. */
static char *slurp(const char *dir, const char *name, size_t *len)
{
    char path[512], *data = NULL;
    snprintf(path, sizeof path, "%s/%s", dir, name);
    return fsio_read_all(path, 1u << 26, &data, len, NULL) ? NULL : data;
}

/* Whether dir/name in a and in b hold the same: the same bytes, or for an
 * OpenEXR file the same pixels (its header has the time it was written). */
static int same_file(const char *a, const char *b, const char *name)
{
    size_t la = 0, lb = 0, nl = strlen(name);
    char *x = slurp(a, name, &la), *y = slurp(b, name, &lb);
    int same = x && y && la == lb && memcmp(x, y, la) == 0;
    if (!same && x && y && nl > 4 && strcmp(name + nl - 4, ".exr") == 0) {
        img p, q;
        glint_err e;
        if (img_read_mem(x, la, &p, &e) == 0) {
            if (img_read_mem(y, lb, &q, &e) == 0) {
                same = p.width == q.width && p.height == q.height &&
                       p.channels == q.channels &&
                       memcmp(p.px, q.px, (size_t)p.width * p.height * p.channels *
                                              sizeof *p.px) == 0;
                img_free(&q);
            }
            img_free(&p);
        }
    }
    free(x);
    free(y);
    return same;
}

/* Every method: a deferred save (glintd's) writes material.json alone when
 * the method names derived files, and material_files_ensure then writes
 * what a full save writes, from the manifest: the same manifest, the same
 * files.  A method without derived files writes them all either way. */
TEST(deferred_files_are_a_full_saves)
{
    char top[] = "/tmp/glint-sweep-XXXXXX", full[64], lazy[64], cmd[96];
    int checked = 0;
    ASSERT_OK(setup());
    ASSERT(mkdtemp(top));
    for (int i = 0; i < METHOD_SMALL_N; i++) {
        const method *meth = method_find(method_small[i][0]);
        void *params = method_params_new(meth);
        unsigned char all[SCENE_MAX_VIEWS];
        prep_request rq = {meth, params, se, all, NULL};
        const char *const *derived;
        prep *pp = NULL;
        material m;
        glint_err e;
        int written = -1, rc;
        memset(all, 1, sizeof all);
        ASSERT_OK(method_small_set(meth, params, method_small[i][1], &e));
        rc = prep_acquire(cc, &rq, NULL, NULL, &pp, &e);
        if (!rc)
            rc = prep_fit(pp, paint_ct, NULL, &m, &e);
        prep_release(cc, pp);
        free(params);
        ASSERT_MSG(rc == 0, "%s: %s", meth->name, e.msg);
        snprintf(full, sizeof full, "%s/%s-full", top, meth->name);
        snprintf(lazy, sizeof lazy, "%s/%s-lazy", top, meth->name);
        ASSERT_MSG(material_save(&m, full, &e) == 0, "%s: %s", meth->name, e.msg);
        ASSERT_MSG(material_save_deferred(&m, lazy, &e) == 0, "%s: %s", meth->name, e.msg);
        derived = m.method->mat->derived_files;
        for (const char *const *f = derived; f && *f; f++) {
            size_t n;
            char *in_lazy = slurp(lazy, *f, &n), *in_full = slurp(full, *f, &n);
            free(in_lazy);
            free(in_full);
            ASSERT_MSG(!in_lazy, "%s: %s written by a deferred save", meth->name, *f);
            ASSERT_MSG(in_full, "%s: a full save lacks %s", meth->name, *f);
        }
        ASSERT_MSG(material_files_ensure(lazy, &written, &e) == 0, "%s: %s", meth->name, e.msg);
        {
            int nd = 0;
            for (const char *const *f = derived; f && *f; f++)
                nd++;
            ASSERT_MSG(written == nd, "%s: %d files written, %d derived", meth->name, written,
                       nd);
        }
        ASSERT_MSG(same_file(full, lazy, "material.json"), "%s: manifests differ", meth->name);
        for (const char *const *f = derived; f && *f; f++)
            ASSERT_MSG(same_file(full, lazy, *f), "%s: %s differs", meth->name, *f);
        printf("  %-8s %s\n", m.method->name,
               derived ? "derived files written on first use, the same as a full save's"
                       : "no derived files: everything saved at once");
        checked += derived != NULL;
        material_free(&m);
    }
    ASSERT(checked >= 3); /* hf3, hf4, hf2d (and auto's choice when it is one of them) */
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", top);
    ASSERT_EQ(system(cmd), 0);
}

TEST_LIST {
    TEST_ENTRY(every_parameter_at_its_ends),
    TEST_ENTRY(extreme_paintings),
    TEST_ENTRY(deferred_files_are_a_full_saves),
};

TEST_MAIN()
