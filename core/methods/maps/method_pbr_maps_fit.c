/* method_pbr_maps_fit.c: the pbr_maps method's fit (method_pbr_maps.h):
 * which of a few physically based materials holds at each texel, found by
 * alternating two steps as k-means does, with pbr fits for centres.
 *
 *   start   product 0 is the pbr fit of every sample; product k the pbr fit
 *           of the samples of the texels the products before it fit worst
 *           (the worst k / (k + 1) of them by mean squared error a sample):
 *           the next material is where the others fail
 *   assign  each reached texel takes the product with the least squared
 *           error over the samples that read it, each weighted as it reads
 *           the texel (bilinearly, as a renderer does; every view
 *           together).  As the squared error is convex, a sample's error
 *           under the blend it renders with is at most the weighted sum of
 *           its errors under each texel's product: the assignment lowers a
 *           bound on the rendered error, so no texel takes a product whose
 *           highlight its neighbours' samples contradict
 *   refit   each product is fitted again (pbr_fit, from the product as it
 *           is and one roughness start) to the samples that fall in its
 *           texels but the tenth it fits worst (samples on a border between
 *           materials hold some of both)
 *
 * until no texel changes or `rounds` rounds.  A product left with fewer
 * samples than pbr_fit needs is dropped.  The coefficient textures are
 * then 1 where a product holds and 0 elsewhere on reached texels; the
 * texels no sample reaches are filled from their neighbours by push-pull
 * (uvtex_fill), so they blend the products around them.
 *
 * Why hard assignment: with coefficients free in [0, 1] per texel (the
 * maps' joint refinement) a texel seen from a direction or two mixes
 * products to fit what it sees, and the mix holds nowhere else: on seed
 * 000's Table 4 (the triceratops, gold stripes on red) products fitted to
 * residuals and refined that way predicted 20 new views at 0.21-0.25 RMS
 * with the painted views at 0.05.  One product a texel makes the colour
 * it shows off the highlight decide its highlight too. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "clock.h"
#include "method_pbr_maps.h"
#include "scene.h"
#include "uvtex.h"
#include "internal/method_maps_int.h"

/* The fraction of a product's samples its refit leaves out (the worst
 * fitted). */
#define PBR_MAPS_TRIM 0.1
/* 1: a round's refit starts from the product as it is and one roughness
 * start (0: from all of pbr's starts) */
#define WARM_REFITS 1
/* (at most 25 iterations for those, 1.6 times faster on the triceratops of
 * bench_maps, predicted its new views at 0.0646 against 0.0617: not kept) */

typedef struct em {
    const method_fit_in *in;
    const pbr_geom *g;
    const pbr_params *pp;
    long n, T;
    int K, M;
    int *tex;          /* n: each sample's texel (the one it falls in) */
    int *t4;           /* 4 n: the four texels a sample reads, bilinearly */
    float *w4;         /* 4 n: and their weights */
    int *hits;         /* T: samples that read a texel (with a weight above 0) */
    double *wsum;      /* T: the weights they read it with */
    int *assign;       /* T: each reached texel's product (-1: none reached) */
    double *sse;       /* T K: squared error of each product over each texel's samples */
    unsigned char *take; /* n */
    pbr_material prod[MATMAP_MAX];
    json_t *info[MATMAP_MAX];
    int changes[PBR_MAPS_ROUNDS_MAX + 1];
    int rounds;
    double rel0;       /* product 0's RMS over the painting's (0 for a black painting) */
    const char *stop;  /* "tolerance" (one product) or "components" */
} em;

static void em_free(em *e)
{
    free(e->tex);
    free(e->t4);
    free(e->w4);
    free(e->hits);
    free(e->wsum);
    free(e->assign);
    free(e->sse);
    free(e->take);
    for (int k = 0; k < MATMAP_MAX; k++)
        json_decref(e->info[k]);
}

static int em_alloc(em *e, glint_err *err)
{
    const samples *s = e->in->s;
    size_t n1 = (size_t)(e->n ? e->n : 1);
    e->tex = malloc(n1 * sizeof *e->tex);
    e->t4 = malloc(4 * n1 * sizeof *e->t4);
    e->w4 = malloc(4 * n1 * sizeof *e->w4);
    e->hits = calloc((size_t)e->T, sizeof *e->hits);
    e->wsum = calloc((size_t)e->T, sizeof *e->wsum);
    e->assign = malloc((size_t)e->T * sizeof *e->assign);
    e->sse = malloc((size_t)e->T * e->K * sizeof *e->sse);
    e->take = malloc((size_t)(e->n ? e->n : 1));
    if (!e->tex || !e->t4 || !e->w4 || !e->hits || !e->wsum || !e->assign || !e->sse ||
        !e->take)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory (maps of %d x %d texels)", e->M,
                             e->M);
    for (long i = 0; i < e->n; i++) {
        int a = (int)(s->uv[2 * i] * e->M), b = (int)(s->uv[2 * i + 1] * e->M);
        size_t t[4];
        double w[4];
        a = a < 0 ? 0 : a >= e->M ? e->M - 1 : a; /* u = 1 in the last column */
        b = b < 0 ? 0 : b >= e->M ? e->M - 1 : b;
        e->tex[i] = b * e->M + a;
        uvtex_footprint(s->uv[2 * i], s->uv[2 * i + 1], e->M, t, w);
        for (int k = 0; k < 4; k++) {
            e->t4[4 * i + k] = (int)t[k];
            e->w4[4 * i + k] = (float)w[k];
            if (w[k] > 0.0) {
                e->hits[t[k]]++;
                e->wsum[t[k]] += w[k];
            }
        }
    }
    for (long t = 0; t < e->T; t++)
        e->assign[t] = e->hits[t] ? 0 : -1;
    return 0;
}

/* Product k: the pbr fit of the samples flagged in e->take; warm: from
 * the product as it is, with one roughness start beside it (a refit of a
 * round: its samples moved little). */
static int fit_product(em *e, int k, int warm, glint_err *err)
{
    const pbr_params *pp = e->pp;
    pbr_spec sp = {pp->lobes, pp->fresnel};
    pbr_fit_opts o = {.starts = warm ? 1 : pp->starts, .max_iter = pp->max_iter,
                      .start_iter = pp->start_iter, .subset = pp->start_samples,
                      .refine = pp->refine_samples, .p0 = warm ? e->prod[k].p : NULL};
    pbr_fit_result *r = malloc(sizeof *r);
    pbr_geom sub;
    float *y = NULL;
    int rc;

    if (!r)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    if ((rc = pbr_geom_pick(e->g, e->in->rgb, e->take, &sub, &y))) {
        free(r);
        return glint_err_set(err, rc, "out of memory (a product's samples)");
    }
    rc = pbr_fit(&sp, &sub, y, &o, r, err);
    if (!rc) {
        json_t *det = pbr_report_determination(&sp, r, r->nsamples_lit == 0);
        e->prod[k].sp = sp;
        memcpy(e->prod[k].p, r->p, sizeof r->p);
        pbr_material_sync(&e->prod[k]);
        json_decref(e->info[k]);
        e->info[k] = json_pack("{s:i, s:f, s:o}", "samples", sub.n, "rms", r->rms, "fit",
                               pbr_report_fit(r));
        if (!e->info[k] || !det) {
            json_decref(det);
            rc = glint_err_set(err, GLINT_ENOMEM, "out of memory");
        } else {
            json_object_update(e->info[k], det);
            json_decref(det);
        }
    }
    pbr_geom_free(&sub);
    free(y);
    free(r);
    return rc;
}

/* Product k's value (f ci) at sample i (OUT m[3]). */
static void product_at(const em *e, int k, long i, double m[3])
{
    const pbr_geom *g = e->g;
    m[0] = m[1] = m[2] = 0.0;
    if (!(g->ci[i] > 0.0 && g->co[i] > 0.0))
        return;
    pbr_brdf(e->prod[k].kd, e->prod[k].lobe, e->prod[k].sp.nlobes, g->ci[i], g->co[i], g->ch[i],
             g->cd[i], m);
    for (int c = 0; c < 3; c++)
        m[c] *= g->ci[i];
}

/* e->sse for products 0..K-1: each sample's squared error under product
 * k added to the four texels it reads, with the weight it reads each. */
static void texel_errors(em *e, int K)
{
    memset(e->sse, 0, (size_t)e->T * e->K * sizeof *e->sse);
    for (long i = 0; i < e->n; i++)
        for (int k = 0; k < K; k++) {
            double m[3], d = 0.0;
            product_at(e, k, i, m);
            for (int c = 0; c < 3; c++) {
                double r = m[c] - e->in->rgb[3 * i + c];
                d += r * r;
            }
            for (int a = 0; a < 4; a++)
                e->sse[(size_t)e->t4[4 * i + a] * e->K + k] += e->w4[4 * i + a] * d;
        }
}

/* Each reached texel to its best of products 0..K-1; returns the changes. */
static int assign(em *e, int K)
{
    int changes = 0;
    texel_errors(e, K);
    for (long t = 0; t < e->T; t++) {
        const double *s = e->sse + (size_t)t * e->K;
        int best = 0;
        if (!e->hits[t])
            continue;
        for (int k = 1; k < K; k++)
            if (s[k] < s[best])
                best = k;
        changes += best != e->assign[t];
        e->assign[t] = best;
    }
    return changes;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* Flag the samples of the texels products 0..k-1 fit worst (the worst
 * k / (k + 1) by mean squared error a sample); returns how many. */
static long take_worst(em *e, int k, double *scratch)
{
    long m = 0, taken = 0;
    double cut;
    texel_errors(e, k);
    for (long t = 0; t < e->T; t++)
        if (e->hits[t]) {
            const double *s = e->sse + (size_t)t * e->K;
            double best = s[0];
            for (int j = 1; j < k; j++)
                best = fmin(best, s[j]);
            scratch[t] = e->wsum[t] > 0.0 ? best / e->wsum[t] : 0.0;
            scratch[e->T + m++] = scratch[t];
        }
    if (!m)
        return 0;
    qsort(scratch + e->T, (size_t)m, sizeof *scratch, cmp_double);
    cut = scratch[e->T + (long)((double)m / (k + 1))];
    for (long i = 0; i < e->n; i++) {
        e->take[i] = scratch[e->tex[i]] >= cut;
        taken += e->take[i];
    }
    return taken;
}

/* Flag the samples of product k's texels but the worst fitted
 * PBR_MAPS_TRIM of them under the product as it is (least trimmed
 * squares: samples that straddle two materials at a border would pull a
 * product towards the other's highlight); returns how many.  scratch: 2 n
 * doubles. */
static long take_product(em *e, int k, double *scratch)
{
    long m = 0, taken = 0;
    double cut = INFINITY;
    for (long i = 0; i < e->n; i++) {
        double v[3], d = 0.0;
        scratch[i] = -1.0;
        if (e->assign[e->tex[i]] != k)
            continue;
        product_at(e, k, i, v);
        for (int c = 0; c < 3; c++)
            d += (v[c] - e->in->rgb[3 * i + c]) * (v[c] - e->in->rgb[3 * i + c]);
        scratch[i] = d;
        scratch[e->n + m++] = d;
    }
    if (m > 0) {
        qsort(scratch + e->n, (size_t)m, sizeof *scratch, cmp_double);
        cut = scratch[e->n + (long)((1.0 - PBR_MAPS_TRIM) * (double)(m - 1))];
    }
    for (long i = 0; i < e->n; i++) {
        e->take[i] = scratch[i] >= 0.0 && scratch[i] <= cut;
        taken += e->take[i];
    }
    return taken;
}

/* The RMS of the painting (every sample, every channel). */
static double painting_rms(const em *e)
{
    double ss = 0.0;
    for (long i = 0; i < 3 * e->n; i++)
        ss += (double)e->in->rgb[i] * e->in->rgb[i];
    return e->n ? sqrt(ss / (3.0 * (double)e->n)) : 0.0;
}

/* The RMS of product k over every sample. */
static double product_rms(const em *e, int k)
{
    double ss = 0.0;
    for (long i = 0; i < e->n; i++) {
        double m[3];
        product_at(e, k, i, m);
        for (int c = 0; c < 3; c++)
            ss += (m[c] - e->in->rgb[3 * i + c]) * (m[c] - e->in->rgb[3 * i + c]);
    }
    return e->n ? sqrt(ss / (3.0 * (double)e->n)) : 0.0;
}

/* The start: product 0 on everything, each next one where the others fail
 * (fewer if a fit has too few samples; none when product 0 leaves at most
 * tol of the painting's RMS: one material).  Returns the products made (OUT
 * *K) or an error. */
static int start(em *e, int *K, double tol, glint_err *err)
{
    double *scratch = malloc(2 * (size_t)e->T * sizeof *scratch);
    int rc = 0, np = 3 + 5 * e->pp->lobes;
    if (!scratch)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    memset(e->take, 1, (size_t)e->n);
    if ((rc = fit_product(e, 0, 0, err)))
        goto done;
    *K = 1;
    e->stop = "components";
    e->rel0 = painting_rms(e) > 0.0 ? product_rms(e, 0) / painting_rms(e) : 0.0;
    if (e->rel0 <= tol) {
        e->stop = "tolerance";
        goto done;
    }
    for (int k = 1; k < e->K; k++) {
        glint_err ignored;
        if (take_worst(e, k, scratch) < 2 * np || fit_product(e, k, 0, &ignored))
            break;
        *K = k + 1;
    }
done:
    free(scratch);
    return rc;
}

/* Drop products no texel holds (compacting the others); returns K. */
static int drop_empty(em *e, int K)
{
    int map[MATMAP_MAX], k2 = 0;
    for (int k = 0; k < K; k++) {
        long held = 0;
        for (long t = 0; t < e->T && !held; t++)
            held = e->assign[t] == k;
        if (held) {
            map[k] = k2;
            if (k2 != k) {
                e->prod[k2] = e->prod[k];
                json_decref(e->info[k2]);
                e->info[k2] = e->info[k];
                e->info[k] = NULL;
            }
            k2++;
        } else {
            map[k] = -1;
        }
    }
    for (long t = 0; t < e->T; t++)
        if (e->assign[t] >= 0)
            e->assign[t] = map[e->assign[t]];
    return k2;
}

/* Alternate assignment and refits; returns the products left (OUT *K). */
static int alternate(em *e, int *K, int rounds, glint_err *err)
{
    int np = 3 + 5 * e->pp->lobes;
    double *scratch = malloc(2 * (size_t)(e->n ? e->n : 1) * sizeof *scratch);
    if (!scratch)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    e->changes[0] = assign(e, *K);
    e->rounds = 0;
    for (int r = 1; r <= rounds; r++) {
        *K = drop_empty(e, *K);
        for (int k = 0; k < *K; k++) {
            glint_err ignored;
            if (take_product(e, k, scratch) >= 2 * np)
                (void)fit_product(e, k, WARM_REFITS, &ignored); /* a failed refit keeps it */
        }
        e->rounds = r;
        if (!(e->changes[r] = assign(e, *K)))
            break;
    }
    free(scratch);
    *K = drop_empty(e, *K);
    return 0;
}

/* The coefficient textures (OUT *coef: K T floats): one-hot on reached
 * texels, push-pull elsewhere. */
static int coefficients(const em *e, int K, float **coef, glint_err *err)
{
    float *c = calloc((size_t)K * e->T, sizeof *c);
    int rc = 0;
    if (!c)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    for (long t = 0; t < e->T; t++)
        if (e->assign[t] >= 0)
            c[(size_t)e->assign[t] * e->T + t] = 1.0f;
    for (int k = 0; k < K && !rc; k++)
        rc = uvtex_fill(c + (size_t)k * e->T, e->hits, e->M, 1, NULL, err);
    if (rc)
        free(c);
    else
        *coef = c;
    return rc;
}

/* The matmap of the products (moved into mm, the infos with them; coef
 * moves in only on success). */
static int make_matmap(em *e, int K, float *coef, matmap *mm, glint_err *err)
{
    memset(mm, 0, sizeof *mm);
    mm->k = K;
    mm->res = e->M;
    mm->coef = coef;
    mm->stop = e->stop;
    mm->refine = "off";
    for (int k = 0; k < K; k++) {
        pbr_material *pm = malloc(sizeof *pm);
        if (!pm) {
            mm->coef = NULL; /* still the caller's, who frees it */
            matmap_free(mm);
            return glint_err_set(err, GLINT_ENOMEM, "out of memory");
        }
        *pm = e->prod[k];
        material_init(&mm->comp[k], &method_pbr, pm, e->info[k]);
        e->info[k] = NULL;
    }
    return 0;
}

/* RMS, max |error| and by view of material m on the painted samples. */
static json_t *painted_errors(const material *m, const samples *s, const float *rgb)
{
    double ss = 0.0, mx = 0.0, vse[SCENE_MAX_VIEWS];
    long vn[SCENE_MAX_VIEWS];
    int nv = s->nviews < SCENE_MAX_VIEWS ? s->nviews : SCENE_MAX_VIEWS;
    memset(vse, 0, sizeof vse);
    memset(vn, 0, sizeof vn);
    for (int i = 0; i < s->n; i++) {
        double n[3], wi[3], wo[3], uv[2] = {s->uv[2 * i], s->uv[2 * i + 1]}, v[3], d2 = 0.0;
        for (int c = 0; c < 3; c++) {
            n[c] = s->nrm[3 * i + c];
            wi[c] = s->wi[3 * i + c];
            wo[c] = s->wo[3 * i + c];
        }
        material_eval_at(m, uv, n, wi, wo, v);
        for (int c = 0; c < 3; c++) {
            double d = v[c] - rgb[3 * i + c];
            d2 += d * d;
            mx = fmax(mx, fabs(d));
        }
        ss += d2;
        if (s->view[i] >= 0 && s->view[i] < nv) {
            vse[s->view[i]] += d2;
            vn[s->view[i]]++;
        }
    }
    return json_pack("{s:f, s:f, s:o}", "rms_painted", s->n ? sqrt(ss / (3.0 * s->n)) : 0.0,
                     "max_abs_painted", mx, "rms_by_view", method_rms_by_view(vse, vn, nv));
}

static json_t *report(const method_fit_in *in, const em *e, int K, double t0)
{
    json_t *prods = json_array(), *ch = json_array();
    for (int k = 0; k < K; k++) {
        long held = 0;
        for (long t = 0; t < e->T; t++)
            held += e->assign[t] == k;
        json_array_append_new(prods, json_pack("{s:I, s:O*}", "texels", (json_int_t)held, "fit",
                                               e->info[k]));
    }
    for (int r = 0; r <= e->rounds; r++)
        json_array_append_new(ch, json_integer(e->changes[r]));
    return json_pack("{s:o, s:{s:s, s:s, s:i}, s:{s:f, s:f}, s:{s:i, s:i, s:o, s:o, s:s, s:f, "
                     "s:s}, s:s}",
                     "params", method_params_to_json(&method_pbr_maps, in->params),
                     "precomputation", "pattern_hash", in->s->hash, "cache_key", in->keys[0],
                     "samples", in->s->n, "seconds", "samples", in->pattern_seconds, "fit",
                     glint_now() - t0, "maps", "components", K, "rounds", e->rounds,
                     "texels_changed", ch, "products", prods, "stop", e->stop,
                     "one_product_rel_rms", e->rel0, "rule",
                     "each reached texel holds the product with the least squared error over "
                     "the samples that read it, weighted as they read it (bilinearly); "
                     "products refitted to their texels' samples until no texel changes; "
                     "texels no sample reaches blend their neighbours' products",
                     "product", "pbr");
}

static int check_input(const method_fit_in *in, glint_err *err)
{
    const samples *s = in->s;
    if (!s->has_pos || !s->uv)
        return glint_err_set(err, GLINT_EINVAL,
                             "pbr_maps: the samples carry no texture coordinates (imported "
                             "samples): paint the scene's views instead");
    for (long i = 0; i < 3L * s->n; i++)
        if (!isfinite(in->rgb[i]))
            return glint_err_set(err, GLINT_ENONFINITE,
                                 "pbr_maps: painted value %ld (sample %ld, channel %ld) is not "
                                 "finite",
                                 i, i / 3, i % 3);
    return 0;
}

int pbr_maps_fit_in(const method_fit_in *in, material *out, glint_err *err)
{
    const pbr_maps_params *p = in->params;
    double t0 = glint_now();
    em e;
    int K = 0, rc;
    float *coef = NULL;
    matmap mm;
    json_t *info, *errs;

    memset(out, 0, sizeof *out);
    if ((rc = check_input(in, err)))
        return rc;
    memset(&e, 0, sizeof e);
    e.in = in;
    e.g = in->levels[0];
    e.pp = &p->pbr;
    e.n = in->s->n;
    e.K = p->components;
    e.M = p->map_res;
    e.T = (long)e.M * e.M;
    /* (one material: its pbr fit as it is, nothing to regroup) */
    if ((rc = em_alloc(&e, err)) || (rc = start(&e, &K, p->tol, err)) ||
        (strcmp(e.stop, "tolerance") && (rc = alternate(&e, &K, p->rounds, err))) ||
        (rc = coefficients(&e, K, &coef, err)))
        goto done;
    info = report(in, &e, K, t0);
    if ((rc = make_matmap(&e, K, coef, &mm, err)))
        goto done;
    coef = NULL;
    if ((rc = maps_material_init(out, &method_pbr_maps, &mm, info, err)))
        goto done;
    errs = painted_errors(out, in->s, in->rgb);
    if (!out->info || !errs) {
        json_decref(errs);
        material_free(out);
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory for the report");
        goto done;
    }
    json_object_set_new(out->info, "errors", errs);
done:
    free(coef);
    em_free(&e);
    return rc;
}
